"""Rounds that cannot learn from their CFD, refused before any work."""

from __future__ import annotations

from mfflap.errors import ConfigError
from mfflap.study_tables import RoundsSettings


def check_rounds(n_rounds: int, tolerance: float, coefficients: str,
                 correct_outputs: bool = False, refit: bool = True,
                 trust_radius: float | None = None, first_order: bool = False,
                 correction_gain: float = 1.0, cfd_repeatability: float | None = None
                 ) -> RoundsSettings:
    """Refuse rounds that cannot learn from their CFD, as the case file's [rounds] table
    does (:class:`~mfflap.study_tables.RoundsSettings`).

    Rounds learn by the refit of identified coefficients on the back-tests, by the output
    correction (``correct_outputs``), or both.

    Returns
    -------
    RoundsSettings
        The settings, checked.

    Raises
    ------
    ConfigError
        Naming the [rounds] key: a value out of range, a setting of the rounds after the
        first for one round, or more than one round where nothing learns (the case file's
        coefficients, ``coefficients`` not ``identified:...``, or ``refit`` False, without an
        output correction), and the combinations
        :class:`~mfflap.study_tables.RoundsSettings` refuses.

    Examples
    --------
    >>> check_rounds(3, 0.1, "identified:uniform").count
    3
    >>> check_rounds(3, 0.1, "case")  # doctest: +IGNORE_EXCEPTION_DETAIL
    Traceback (most recent call last):
    mfflap.errors.ConfigError: rounds.count: ... every round would optimise the same motions
    """
    settings = RoundsSettings(count=n_rounds, tolerance=tolerance,
                              correct_outputs=correct_outputs, refit=refit,
                              trust_radius=trust_radius, first_order=first_order,
                              correction_gain=correction_gain,
                              cfd_repeatability=cfd_repeatability)
    if n_rounds > 1 and not correct_outputs and not coefficients.startswith("identified:"):
        raise ConfigError(
            "rounds.count > 1 refits the model on each round's back-tests, which only "
            f"identified coefficients take up; with the coefficients {coefficients!r} every "
            "round would optimise the same motions: give optimisation.coefficients a "
            "weighting (uniform, low, high) or set rounds.correct_outputs = true",
            key="rounds.count")
    return settings


__all__ = ["check_rounds"]
