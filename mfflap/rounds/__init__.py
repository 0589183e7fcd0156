"""CFD in the loop: rounds of the main job (``mfflap run`` with ``[rounds] count = N``).

The model optimises its motions where it has never been checked (three of the four shipped
optima lie outside the identification data, :mod:`mfflap.identification.coverage`), and
the back-test says by how much it is wrong there. Each round here feeds that CFD back: it
runs the whole main job (:func:`mfflap.pipeline.run_study`) with the identification data
pooled with the back-test records of every round before, so the model is refitted on the
motions it optimised, optimises again, and is back-tested on the new optima, which its fit
has not seen. The rounds stop when

- the model predicts the CFD mean thrust and mean input power of every back-tested motion
  of the round within the tolerance (converged),
- the round's optimised motions are those of an earlier round (a fixed point: the next round
  would fit the same data; with filtered output corrections, not a stop: the filter still
  moves the scales),
- a motion could not be back-tested, or the identification or optimisation failed (the next
  round would learn nothing new), or Ctrl-C stopped the round,
- or the rounds asked for are done.

The back-test records of every round are kept in ``<out>/loop_records`` (one per motion);
they are looked up before the shipped fixtures and, live, before a new OpenFOAM run, so a
motion repeated from an earlier round is not run again and the same command run again (after
a Ctrl-C) finds the CFD done before.

With ``refit`` False (``rounds.refit = false``) or the case file's coefficients, the back-tests are
not pooled into the fits: every round optimises with round 1's coefficients, and only the
output correction learns from the CFD (the classical modifier adaptation of a fixed model).

With ``correct_outputs`` (``rounds.correct_outputs``), round k >= 2 also corrects the model's
outputs: each beta is optimised with the model's mean thrust and power scaled to predict
the CFD means of round k - 1's optimum of that beta, measured with round k's refitted model
(:mod:`mfflap.optimisation.output_correction`), and the error counted is that of the
corrected prediction, the one the optimiser relied on. If the rounds reach a fixed point,
the corrected model predicts CFD's means there. With ``correction_gain`` K < 1
(``rounds.correction_gain``), the scales move only that fraction of the way from those the last
optimum was optimised with to the measured ones (a first-order filter, the usual cure for
the oscillation of the undamped correction).

The prediction checked is made of the model's means as the optimiser saw them (at the
motion's N samples of its scheme, :func:`mfflap.performance.discrete_means`), the ones the
correction's scales are measured with, so that at a fixed point it is CFD's exactly; the
back-test reports keep the model on the kinematics CFD imposed, which differs by the
scheme's discretisation.

With ``trust_radius`` (``rounds.trust_radius``), each round's optimum of a beta is kept near the
last one CFD confirmed (:mod:`mfflap.optimisation.trust_region`); the rounds then converge
only where no optimum is on its region's boundary and no step was refused, and stop when a
region collapses. With ``first_order`` (``rounds.first_order``) the corrected objective also gets
a slope through the earlier back-tested motions of the beta near the centre, so that it is
CFD's objective there too
(:meth:`~mfflap.optimisation.output_correction.OutputCorrection.with_slopes`); the predicted
means stay the scaled ones.

Only motions whose CFD the round's fit has not seen count (a motion repeated from an earlier
round is in the fit). A motion's mean thrust error counts only where its CFD mean thrust is at least
:data:`THRUST_FLOOR` of the largest CFD mean thrust among the round's motions: a motion of
almost no net thrust (beta = 1) has a relative thrust error of no meaning. Its power error
counts.

The package's modules: :mod:`~mfflap.rounds.checks` (the model against CFD per motion),
:mod:`~mfflap.rounds.summary` (a round, and the rounds as run),
:mod:`~mfflap.rounds.refusals` (rounds that cannot learn), :mod:`~mfflap.rounds.steps`
(what a round hands the next: correction points, trust steps),
:mod:`~mfflap.rounds.loop` (the rounds and why they stop) and
:mod:`~mfflap.rounds.output` (``rounds.h5``; its report, ``rounds.png`` and ``rounds.html``,
is :mod:`mfflap.reports.rounds`'s).
"""

from mfflap.rounds.checks import THRUST_FLOOR, MotionCheck, motion_checks, optimised_means
from mfflap.rounds.loop import RECORDS_FOLDER, run_rounds, stop_reason
from mfflap.rounds.output import write_rounds_results
from mfflap.rounds.refusals import check_rounds
from mfflap.rounds.steps import correction_points, trust_steps
from mfflap.rounds.summary import LoopResult, RoundSummary, describe_round

__all__ = [
    "RECORDS_FOLDER",
    "THRUST_FLOOR",
    "LoopResult",
    "MotionCheck",
    "RoundSummary",
    "check_rounds",
    "correction_points",
    "describe_round",
    "motion_checks",
    "optimised_means",
    "run_rounds",
    "stop_reason",
    "trust_steps",
    "write_rounds_results",
]
