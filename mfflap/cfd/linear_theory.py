"""A CFD run's loads against linear (thin-aerofoil) theory of the same imposed motion."""

from __future__ import annotations

import numpy as np

from mfflap.cfd.imposed_motion import imposed_state
from mfflap.hydro.loads import Loads
from mfflap.hydro.thin_aerofoil import thin_aerofoil_loads_at
from mfflap.kinematics.continuous import Motion
from mfflap.kinematics.state import KinematicState
from mfflap.metrics import nrmse, pearson, time_mean
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.performance import thrust_and_power


def compare_with_theory(motion: Motion, ramp_time: float, state: KinematicState,
                        cfd: Loads, keep: np.ndarray, plate: Plate | None = None,
                        fluid: Fluid | None = None, stream: FreeStream | None = None
                        ) -> tuple[dict[str, float], Loads]:
    """CFD loads of ``motion`` (imposed from rest with ``ramp_time``) against linear theory.

    Returns the theory's effective incidence, its mean input power and its NRMSE and Pearson
    against the CFD's F_n and M over the samples ``keep`` (keys ``max_effective_incidence_deg``,
    ``mean_power``, ``nrmse_normal_force``, ``pearson_normal_force``, ``nrmse_moment``,
    ``pearson_moment``), and the theory's loads on ``state``'s time base.
    """
    theory = thin_aerofoil_loads_at(lambda t: imposed_state(motion, t, ramp_time), state.time,
                                    plate, fluid, stream)
    _, power = thrust_and_power(theory, state)
    out = {"max_effective_incidence_deg": theory.metadata["max_effective_incidence_deg"],
           "mean_power": time_mean(state.time[keep], power[keep])}
    for name in ("normal_force", "moment"):
        a, b = getattr(theory, name)[keep], getattr(cfd, name)[keep]
        out[f"nrmse_{name}"] = float(nrmse(a, b))
        out[f"pearson_{name}"] = float(pearson(a, b))
    return out, theory
