"""The built-in NumPy Monte Carlo engine (same scene, same skies as the Radiance engine)."""

from radtree.engines.numpy.engine import DEFAULT_OPTIONS, ENGINE_NAME, TraceOptions, describe
from radtree.engines.numpy.tracing import trace, trace_hour

__all__ = ["DEFAULT_OPTIONS", "ENGINE_NAME", "TraceOptions", "describe", "trace", "trace_hour"]
