"""Laminar skin friction on both faces of the plate (Blasius)."""

from __future__ import annotations

import numpy as np

from mfflap.gap.candidates.base import register
from mfflap.gap.candidates.friction import FlatPlateFriction


@register
class LaminarSkinFriction(FlatPlateFriction):
    """Blasius' laminar flat-plate law C_f = 1.328 Re^-1/2 on both faces.

    The paper's plate runs at chord Reynolds numbers of 5e4-2e5, below a flat plate's
    transition (about 5e5), where the laminar law holds; :mod:`.turbulent_skin_friction` is
    the turbulent one, for a tripped or rough plate. The two differ only in the Reynolds
    exponent and are grouped as one family.
    """

    name = "laminar_skin_friction"
    physical_name = "laminar skin friction (Blasius)"
    coefficient_name = "multiplier k of C_f = 1.328 Re^-0.5 (flat plate: 1)"

    def friction_coefficient(self, reynolds):
        return 1.328 / np.sqrt(reynolds)
