"""Forward light tracing (photons from the sun and sky to patch detectors): a third estimator."""

from radtree.engines.forward.run import ForwardResult, trace_forward
from radtree.engines.forward.settings import ForwardSettings

__all__ = ["ForwardResult", "ForwardSettings", "trace_forward"]
