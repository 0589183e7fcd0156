"""A test motion table (CSV) shared by the tests of several packages: a heave and a pitch
that start at rest, in degrees or radians."""

from pathlib import Path

import numpy as np

T = np.linspace(0.0, 2.0, 81)
HEAVE = 0.1 * np.sin(2 * np.pi * T) ** 2  # starts at rest at 0
PITCH_DEG = 8.0 * (1 - np.cos(np.pi * T))


def write_table(path: Path, pitch_column: str = "pitch_angle_deg", comment: bool = True) -> Path:
    pitch = PITCH_DEG if pitch_column == "pitch_angle_deg" else np.radians(PITCH_DEG)
    lines = ["# heave and pitch of a test motion"] if comment else []
    lines.append(f"heave_position,time,{pitch_column},note")
    lines += [f"{float(h)!r},{float(t)!r},{float(p)!r},0"
              for t, h, p in zip(T, HEAVE, pitch, strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path
