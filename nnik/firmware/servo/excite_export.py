"""`nnik excite`'s firmware (issue 28 item 3): an Arduino library for the Uno that plays the
excitation's duty table on both motors through the servo runtime (codegen/arduino/src/nnik_servo.c:
encoder interrupts, Timer2 PWM + DIR, the Timer1 tick), logs every tick over serial and stops the
motors at the end. The table player sits behind the controller interface (nnik_ctl_excite.c), so
the runtime is the closed-loop build's, byte for byte.

    write_excite_library(d, cfg, duties_h, ticks, start, name="xy_table") -> {"libname", "example", ...}

The serial log (115200 baud) is `nnik identify`'s format with duty fractions (identify --supply V,
V the supply the motors actually ran on): `t,u_x,u_y,count_x,count_y`, t = k x tick with 6
decimals, u = duty / duty_max with 6 decimals (rounded half away from zero), the counts the tick
latched; then one `# end: ...` comment (identify skips it). serial_log() predicts it byte for byte.
A line is at most 55 bytes, 38-42 on the shipped scenario: 8,100 B/s at 5 ms, under the 11,520 B/s
that 115200 baud (10 bits a byte) carries; a ring of 8 rows absorbs jitter, and a row the ring had no
room for is counted in the end line.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from nnik.emit.c_text import c_comment_safe
from nnik.errors import NnikError
from nnik.firmware.arduino import homepage
from nnik.firmware.servo.build import SRC, copy_runtime, tick_ocr1a
from nnik.firmware.servo.export import write_library_files
from nnik.implementations.servo.base import FixedGains

VERSION = "0.1.0"
HEADER = "t,u_x,u_y,count_x,count_y"
SERIAL_BYTES_S = 115200 // 10  # 8N1: 10 bits a byte
SOURCES = ("nnik_ctl_excite.c", "nnik_ctl.h", "nnik_excite.h")


def tick_us(tick_s: float) -> int:
    """The tick in whole microseconds (the log's time column is printed from it exactly)."""
    us = round(tick_s * 1e6)
    if us < 1 or abs(tick_s * 1e6 - us) > 1e-6 * us:
        raise NnikError(f"tick {tick_s:g} s: the excitation firmware logs time in whole microseconds")
    return us


def _fraction(d: int, duty_max: int) -> str:
    q = (abs(d) * 1_000_000 + duty_max // 2) // duty_max
    return f"{'-' if d < 0 else ''}{q // 1_000_000}.{q % 1_000_000:06d}"


def check_serial_rate(text: str, tick_s: float) -> None:
    """Refuse a log whose longest line, once a tick, is more than 115200 baud carries."""
    longest = max(len(line) + 1 for line in text.splitlines()[1:-1])
    if longest / tick_s > SERIAL_BYTES_S:
        raise NnikError(f"the serial log's lines (up to {longest} bytes a {tick_s * 1e3:g} ms tick, "
                        f"{longest / tick_s:,.0f} B/s) are more than 115200 baud carries ({SERIAL_BYTES_S:,} B/s)")


def serial_log(duty, counts, tick_s: float, duty_max: int, lost: int = 0) -> str:
    """The text the firmware prints for these duties (N, 2) and latched counts (N, 2)."""
    us = tick_us(tick_s)
    rows = [f"{k * us // 1_000_000}.{k * us % 1_000_000:06d},{_fraction(d[0], duty_max)},{_fraction(d[1], duty_max)},"
            f"{c[0]},{c[1]}" for k, (d, c) in enumerate(zip(np.asarray(duty).tolist(), np.asarray(counts).tolist()))]
    end = f"# end: {len(rows)} ticks played, motors stopped, lines lost {lost}"
    return "\n".join([HEADER, *rows, end]) + "\n"


class TablePlayer(FixedGains):
    """The firmware's Python model (the nnik_ctl interface): duty[k] at tick k, then 0; no weights
    (checksum 0)."""

    kind = "excite"

    def __init__(self, duty):
        self.duty = np.asarray(duty, dtype=np.int64).reshape(-1, 2)
        self.k = 0

    def reset(self) -> None:
        self.k = 0

    def tick(self, ref, pos) -> tuple[int, int]:
        k, self.k = self.k, self.k + 1
        return (int(self.duty[k, 0]), int(self.duty[k, 1])) if k < len(self.duty) else (0, 0)


def write_excite_library(d: Path, cfg, duties_h: str, ticks: int, start, name: str = "xy_table",
                         source: str = "nnik") -> dict:
    """The library into the new folder d (its name is the library's: nnik_<name>_excite)."""
    ocr = tick_ocr1a(cfg.tick_s)
    tick_us(cfg.tick_s)
    libname = d.name
    example = f"{name}_excite"
    ctx = dict(name=name, libname=libname, version=VERSION, tick_ms=f"{cfg.tick_s * 1e3:g}", homepage=homepage(),
               source=c_comment_safe(source), ticks=ticks, table_bytes=4 * ticks, x0=int(start[0]), y0=int(start[1]),
               example=example, libdir_name=libname)
    src = d / "src"
    copy_runtime(src)
    for f in SOURCES:
        shutil.copy(SRC / f, src / f)
    (src / "nnik_excite_duties.h").write_text(duties_h)
    (src / "nnik_servo_config.h").write_text(
        f"/* nnik excite: the runtime's tick ({cfg.tick_s * 1e3:g} ms); the controller is the table player */\n"
        f"#ifndef NNIK_SERVO_CONFIG_H\n#define NNIK_SERVO_CONFIG_H\n#ifndef NNIK_SERVO_OCR1A\n"
        f"#define NNIK_SERVO_OCR1A {ocr}\n#endif\n#endif /* NNIK_SERVO_CONFIG_H */\n")
    write_library_files(d, ctx, "excite_library.properties.j2", "excite.ino.j2")
    return {"libname": libname, "example": example, "table_bytes": 4 * ticks}
