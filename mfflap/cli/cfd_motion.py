"""The motion a ``mfflap cfd`` command writes or parses: the case file's [motion], or any
motion from a CSV table (``--motion-table``, ``--end-time``)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click
import numpy as np

from mfflap.cli.options import POSITIVE, refuse_given

if TYPE_CHECKING:
    from mfflap.kinematics.continuous import TabulatedMotion


def motion_table_options(note: str):
    """--motion-table and --end-time, for the commands that take any motion."""
    def decorate(command):
        command = click.option(
            "--end-time", type=POSITIVE, default=None,
            help="With --motion-table: simulated time, s (default: the table's last row).",
        )(command)
        return click.option(
            "--motion-table", type=click.Path(dir_okay=False, exists=True, path_type=Path),
            default=None,
            help="CSV of any motion instead of the case file's [motion]: columns time (s, "
                 "from 0), heave_position (m), pitch_angle (rad) or pitch_angle_deg. --cycles "
                 f"does not apply. {note}".strip(),
        )(command)
    return decorate


def motion_and_end_time(case, motion_table: Path | None, end_time: float | None,
                         cycles: float):
    """The motion a command writes or parses, and its end time: the case file's [motion]
    over ``cycles`` periods, or a user's table up to ``end_time`` (default its last row)."""
    if motion_table is None:
        if end_time is not None:
            raise click.UsageError("--end-time goes with --motion-table; the case file's "
                                   "motion runs for --cycles periods")
        end_time = cycles / case.motion.frequency
        case.motion.check_upright(end_time, f"--cycles {cycles:g}", source=case.source)
        return case.motion.build(), end_time
    from mfflap.errors import MotionError
    from mfflap.kinematics.table_file import read_motion_table, table_end_time

    refuse_given(("cycles",), "the case file's [motion]; a --motion-table runs to --end-time "
                              "(default: the table's last row)")
    motion = read_motion_table(motion_table, case.plate.chord)
    try:
        end_time = table_end_time(motion, end_time)
    except MotionError as exc:
        raise click.BadParameter(str(exc), param_hint="--end-time") from exc
    warn_pitch_past_upright(motion, motion_table, end_time)
    return motion, end_time


def warn_pitch_past_upright(motion: TabulatedMotion, motion_table: Path,
                             end_time: float) -> None:
    """Warn on stderr when a table's pitch reaches 90 deg or more up to ``end_time``: most
    likely degrees in the ``pitch_angle`` column, which is in rad."""
    from mfflap.kinematics.continuous import UPRIGHT_PITCH
    from mfflap.kinematics.table_file import largest_pitch

    pitch, time = largest_pitch(motion, end_time)
    if abs(pitch) >= UPRIGHT_PITCH:
        click.echo(f"warning: {motion_table}: the pitch reaches {np.degrees(pitch):.4g} deg at "
                   f"t = {time:g} s, past the {np.degrees(UPRIGHT_PITCH):g} deg at which the "
                   "plate stands across the stream (the column pitch_angle is in rad, "
                   "pitch_angle_deg in degrees)", err=True)


def warn_not_at_rest(motion, ramp_time: float, end_time: float) -> None:
    """Warn on stderr when the imposed motion starts with a rate (an impulsive start, the
    same in every solver but a start-up transient in the forces), naming the rates and the
    remedy."""
    from mfflap.cfd.imposed_motion import not_at_rest

    moving = not_at_rest(motion, ramp_time, end_time)
    if moving:
        click.echo("warning: the motion does not start at rest ("
                   + ", ".join(f"{name} {value:.3g} {unit}"
                               for name, (value, unit) in moving.items())
                   + "): every solver starts it impulsively; --ramp-time starts it at rest",
                   err=True)


__all__ = ["motion_and_end_time", "motion_table_options", "warn_not_at_rest",
           "warn_pitch_past_upright"]
