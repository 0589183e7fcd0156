"""Turbulent skin friction on both faces of the plate."""

from __future__ import annotations

from mfflap.gap.candidates.base import register
from mfflap.gap.candidates.friction import FlatPlateFriction


@register
class TurbulentSkinFriction(FlatPlateFriction):
    """The turbulent flat-plate law C_f = 0.074 Re^-1/5 on both faces (a tripped or rough
    plate; :mod:`.laminar_skin_friction` is the laminar one)."""

    name = "turbulent_skin_friction"
    physical_name = "turbulent skin friction (flat-plate 1/5-power law)"
    coefficient_name = "multiplier k of C_f = 0.074 Re^-0.2 (flat plate: 1)"

    def friction_coefficient(self, reynolds):
        return 0.074 * reynolds**-0.2
