"""Build the servo firmware for the ATmega328P (bare avr-gcc -Os, no Arduino core, so nothing but
the encoder and tick interrupts runs): the runtime codegen/arduino/src/nnik_servo.c, the
controller's C (nnik.implementations.servo.emit_c) and the co-simulation's main and reference feed
(codegen/harness/arduino/nnik_servo_feed.c: the harness writes each tick's reference into
nnik_servo_feed). Also builds the lockstep harness codegen/harness/arduino/nnik_simavr_servo.c
against libsimavr (cached by its source's hash, as the G-code runners are)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from nnik.emit.templating import CODEGEN
from nnik.errors import NnikError
from nnik.firmware.gcode.chip import _build_host_tool
from nnik.implementations.servo.emit_c import write_controller_c
from nnik.targets.avr import elf_sizes
from nnik.targets.toolchain import HARNESS_DIR, TargetError, find_tool, run

CLOCK_HZ = 16_000_000
PRESCALE = 8  # Timer1's
MCU = "atmega328p"
FLASH_BYTES, RAM_BYTES = 32 * 1024 - 512, 2048  # the Uno: optiboot takes 512 B
SRC = CODEGEN / "arduino" / "src"
RUNTIME = ("nnik_servo.c",)
RUNTIME_HEADERS = ("nnik_servo.h",)
FEED = HARNESS_DIR / "arduino" / "nnik_servo_feed.c"
HARNESS_SRC = HARNESS_DIR / "arduino" / "nnik_simavr_servo.c"
SYMBOLS = ("nnik_servo_feed", "nnik_servo_count", "nnik_servo_pos")
# a learning controller's weight checksum (nnik_servo.c publishes its nnik_ctl_sum each tick; with a
# fixed-gain controller it is never written and a linker may drop it): address 0 when absent, which
# the harness answers as checksum 0
OPTIONAL_SYMBOLS = ("nnik_servo_sum",)


@dataclass(frozen=True)
class ServoFirmware:
    elf: Path
    ocr1a: int
    flash_bytes: int
    ram_bytes: int
    symbols: dict  # name -> SRAM address (avr-nm's 0x800000 data offset removed)

    @property
    def period_cycles(self) -> int:
        return (self.ocr1a + 1) * PRESCALE


def tick_ocr1a(tick_s: float) -> int:
    """Timer1's OCR1A for the tick (CTC, prescaler 8, 16 MHz); a tick it cannot make exactly, or
    out of its 16 bits, -> NnikError."""
    cycles = tick_s * CLOCK_HZ / PRESCALE
    ocr = round(cycles) - 1
    if not 1 <= ocr <= 0xFFFF or abs(cycles - (ocr + 1)) > 1e-6 * cycles:
        raise NnikError(f"tick {tick_s:g} s: the Uno's Timer1 (prescaler {PRESCALE}) makes ticks of whole "
                        f"0.5 us steps from 1 us to {0x10000 * PRESCALE / CLOCK_HZ * 1e3:g} ms")
    return ocr


def copy_runtime(outdir: Path) -> list[Path]:
    """The runtime's sources and headers into outdir; returns the .c paths."""
    outdir.mkdir(parents=True, exist_ok=True)
    for f in RUNTIME + RUNTIME_HEADERS:
        (outdir / f).write_bytes((SRC / f).read_bytes())
    return [outdir / f for f in RUNTIME]


def _symbols(elf: Path, cwd: Path, names=SYMBOLS) -> dict:
    """names' SRAM addresses (each required) and OPTIONAL_SYMBOLS' (0 when absent)."""
    res = run([find_tool("avr-nm"), elf], "avr-nm", cwd=cwd)
    found = dict.fromkeys(OPTIONAL_SYMBOLS, 0)
    for line in res.stdout.splitlines():
        parts = line.split()
        if len(parts) == 3 and (parts[2] in names or parts[2] in OPTIONAL_SYMBOLS):
            found[parts[2]] = int(parts[0], 16) - 0x800000
    missing = [s for s in names if s not in found]
    if missing:
        raise TargetError(f"servo firmware: no symbol {', '.join(missing)} in {elf.name}")
    return found


def build_firmware(controller, tick_s: float, workdir: Path) -> ServoFirmware:
    """The co-simulation firmware for `controller` (a nnik.implementations.servo controller) at
    this tick, in workdir; flash and RAM checked against the Uno's."""
    for tool in ("avr-gcc", "avr-nm", "avr-size"):
        if find_tool(tool) is None:
            raise TargetError(f"{tool} not found; run scripts/install_toolchains.sh")
    ocr = tick_ocr1a(tick_s)
    workdir = Path(workdir).resolve()
    src = workdir / "src"
    srcs = [*write_controller_c(controller, src), *copy_runtime(src), FEED]
    elf = workdir / "servo.elf"
    run([find_tool("avr-gcc"), f"-mmcu={MCU}", f"-DF_CPU={CLOCK_HZ}UL", f"-DNNIK_SERVO_OCR1A={ocr}", "-Os", "-Wall",
         "-std=gnu11", "-ffunction-sections", "-fdata-sections", "-Wl,--gc-sections", f"-I{src}", *srcs, "-o", elf],
        "build the servo firmware", cwd=workdir, log=workdir / "build.log")
    size = elf_sizes(elf, workdir)
    flash, ram = size["flash"], size["ram"]
    if flash > FLASH_BYTES or ram > RAM_BYTES:
        raise TargetError(f"servo firmware does not fit the Uno: flash {flash} of {FLASH_BYTES} B, RAM {ram} of {RAM_BYTES} B")
    return ServoFirmware(elf, ocr, flash, ram, _symbols(elf, workdir))


def sketch_firmware(elf: Path, tick_s: float) -> ServoFirmware:
    """An exported sketch's ELF (it plays its own stored job: no reference feed) for the
    co-simulation."""
    elf = Path(elf).resolve()
    size = elf_sizes(elf, elf.parent)
    flash, ram = size["flash"], size["ram"]
    syms = _symbols(elf, elf.parent, ("nnik_servo_count", "nnik_servo_pos"))
    return ServoFirmware(elf, tick_ocr1a(tick_s), flash, ram, {**syms, "nnik_servo_feed": 0})


def build_harness(workdir: Path) -> Path:
    """The lockstep simavr runner (codegen/harness/arduino/nnik_simavr_servo.c)."""
    return _build_host_tool(HARNESS_SRC, Path(workdir), ["-lsimavr"], "build the simavr servo harness")

