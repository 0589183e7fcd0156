"""Rounds that cannot learn from their CFD, refused before any work."""

from __future__ import annotations

import numpy as np

from mfflap.errors import ConfigError
from mfflap.optimisation.trust_region import check_radius, check_repeatability


def check_rounds(n_rounds: int, tolerance: float, coefficients: str,
                 correct_outputs: bool = False, refit: bool = True,
                 trust_radius: float | None = None, first_order: bool = False,
                 correction_gain: float = 1.0, cfd_repeatability: float | None = None
                 ) -> None:
    """Refuse rounds that cannot learn from their CFD.

    Rounds learn by the refit of identified coefficients on the back-tests, by the output
    correction (``correct_outputs``), or both.

    Raises
    ------
    ConfigError
        ``n_rounds`` < 1, ``tolerance`` not in (0, 1), or more than one round where nothing
        learns: neither a refit (the case file's coefficients, or ``refit`` False) nor an
        output correction, so that every round would optimise the same motions; a trust
        region's radius not in (0, :data:`~mfflap.optimisation.trust_region.MAX_RADIUS`], or
        a trust region for one round (it bounds the rounds after the first); slopes
        (``first_order``) without the output correction, its measured scales (gain 1) and a
        trust region; a CFD repeatability not in (0, 1) or without a trust region.
    """
    if n_rounds < 1:
        raise ConfigError(f"--rounds must be >= 1, got {n_rounds}", key="rounds")
    if not (np.isfinite(tolerance) and 0 < tolerance < 1):
        raise ConfigError(f"--loop-tolerance must be a fraction in (0, 1), got {tolerance}",
                          key="loop_tolerance")
    if n_rounds > 1 and not correct_outputs:
        if not coefficients.startswith("identified:"):
            raise ConfigError(
                "--rounds > 1 refits the model on each round's back-tests, which only "
                f"identified coefficients take up; with --coefficients {coefficients} every "
                "round would optimise the same motions: add --coefficients identified:uniform "
                "(or low, high), or --correct-outputs", key="rounds")
        if not refit:
            raise ConfigError("--no-refit keeps the coefficients of round 1, so without "
                              "--correct-outputs every round would optimise the same motions",
                              key="refit")
    if trust_radius is not None:

        check_radius(trust_radius)
        if n_rounds < 2:
            raise ConfigError("--trust-region bounds each round's optimum about the last one "
                              "CFD confirmed, so it needs --rounds 2 or more", key="trust_region")
    if cfd_repeatability is not None:

        check_repeatability(cfd_repeatability)
        if trust_radius is None:
            raise ConfigError("--cfd-repeatability relaxes the trust region's judgement of "
                              "each step by CFD's noise, so it needs --trust-region",
                              key="cfd_repeatability")
    if first_order:
        missing = [flag for flag, given in (("--correct-outputs", correct_outputs),
                                            ("--trust-region", trust_radius is not None))
                   if not given]
        if missing:
            raise ConfigError("--first-order gives the corrected objective a slope, which "
                              "without a trust region would lead the optimiser off along a "
                              f"secant; it needs {' and '.join(missing)}", key="first_order")
        if correction_gain != 1.0:
            raise ConfigError("--first-order meets CFD at the centre with the measured "
                              f"scales; --correction-gain {correction_gain:g} filters them",
                              key="first_order")


__all__ = ["check_rounds"]
