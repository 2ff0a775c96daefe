"""The physics suite (``radtree verify``): abstract canopies and estimator agreement."""

from radtree.verify.checks import (
    Check,
    agreement_checks,
    energy_checks,
    sphere_checks,
    transmission_checks,
)
from radtree.verify.suite import VerifyOutcome, run_verify

__all__ = ["Check", "VerifyOutcome", "agreement_checks", "energy_checks", "run_verify",
           "sphere_checks", "transmission_checks"]
