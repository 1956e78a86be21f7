"""The Uno's closed-loop export with a neural controller (issue 29 item 8): the library runs nn_axes or
nn_vector from its (pretrained) weights, builds with arduino-mk and fits the Uno with the largest job
nnik lets it store (as the largest fixed-gain controller, ccc, with its own); one byte more is refused; the built sketch on the simulated Uno, closed loop with
the plant, gives the model's duty and weights' checksum at every tick."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from nnik.errors import NnikError
from nnik.firmware.servo.build import FLASH_BYTES, RAM_BYTES, sketch_firmware
from nnik.firmware.servo.export import export_servo_library, job_flash_bytes
from nnik.firmware.servo.job_pack import pack, unpack
from nnik.implementations.servo import NEURAL, make
from nnik.targets.avr import elf_sizes
from tests.firmware.servo.chip_fixtures import controller, shipped_cfg
from tests.implementations.servo.nn_params import seeded_nn_params


def arduino_mk() -> None:
    if not Path("/usr/share/arduino/Arduino.mk").is_file() or shutil.which("make") is None \
            or shutil.which("simavr") is None:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail("arduino-mk or simavr not installed")
        pytest.skip("arduino-mk or simavr not installed (run scripts/install_toolchains.sh)")


def build(libdir: Path) -> Path:
    ex = libdir / "examples" / "xy_table_servo"
    r = subprocess.run(["make", "-s"], cwd=ex, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-800:]
    return next((ex / "build-uno").glob("*.elf"))


def one_byte_ticks(n: int) -> np.ndarray:
    """n ticks stored one byte each: alternately one count on X and one on Y (never a repeat)."""
    steps = np.where((np.arange(n) % 2 == 0)[:, None], [1, 0], [0, 1])
    return np.cumsum(steps, axis=0).astype(np.int64)


@pytest.mark.parametrize("kind", ("ccc", *NEURAL))  # ccc: the largest fixed-gain controller
def test_the_largest_job_it_stores_builds_and_fits_the_uno(kind, tmp_path):
    arduino_mk()
    cfg = shipped_cfg()
    ctl = make(kind, seeded_nn_params(kind, 1, cfg), cfg) if kind in NEURAL else controller(kind, cfg)
    room = job_flash_bytes(ctl)
    ref = one_byte_ticks(room)
    assert len(pack(ref)) == room
    with pytest.raises(NnikError, match="do not fit"):
        export_servo_library(tmp_path / "over", cfg, ctl, one_byte_ticks(room + 1))
    assert not (tmp_path / "over").exists()
    res = export_servo_library(tmp_path / "lib", cfg, ctl, ref)
    assert res["job_bytes"] == room
    size = elf_sizes(build(tmp_path / "lib"), tmp_path)
    assert size["flash"] <= FLASH_BYTES and size["ram"] <= RAM_BYTES
    assert size["flash"] > room


@pytest.mark.parametrize("kind", NEURAL)
def test_the_exported_sketch_learns_as_the_model(kind, tmp_path):
    arduino_mk()
    from nnik.firmware.servo.cosim import run

    cfg = shipped_cfg()
    params = seeded_nn_params(kind, 5, cfg)
    start = (1200, 800)
    ref = np.concatenate([np.tile([1200, 800], (10, 1)), np.tile([9000, -3000], (120, 1)),
                          np.array([9000, -3000]) + np.cumsum(np.tile([3, -2], (60, 1)), axis=0)])
    lib = tmp_path / "libraries" / "nnik_xy"
    export_servo_library(lib, cfg, make(kind, params, cfg), ref, start)
    config = (lib / "src" / "nnik_servo_config.h").read_text()
    assert f"NNIK_CTL_{kind.upper()} 1" in config and "NNIK_NN_W1_INIT" in config
    fw = sketch_firmware(build(lib), cfg.tick_s)
    assert fw.symbols["nnik_servo_sum"] > 0  # kept by the sketch's link-time optimisation
    played = unpack(pack(ref, start), start, len(ref) + 5)
    tr = run(fw, cfg, make(kind, params, cfg), played, tmp_path / "run", start_counts=start)
    assert tr.mismatches == 0 and tr.lost_counts == 0
    assert len(set(tr.chip_sum.tolist())) > 10 and np.abs(tr.chip_duty).max() > 0
