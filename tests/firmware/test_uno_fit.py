"""The Uno's sender build carries the build options that fit its flash, the fewest left out
(nnik.firmware.uno_fit), and the Mega's build every option (issue 26 item 6)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from nnik import pipeline
from nnik.firmware.arduino import export_arduino
from nnik.firmware.config import FEATURES, default_machine, shaper_taps
from nnik.firmware.gcode import chip
from nnik.firmware.ik_oracle import load_scenario_of
from nnik.firmware.uno_fit import DROPS, uno_features
from nnik.targets.toolchain import TargetError
from tests.firmware.gcode.conftest import require_chip


@pytest.mark.parametrize("shaper", ["none", "zvd"])
def test_the_uno_build_fits_with_the_fewest_options_left_out(corexy_run, shaper, tmp_path):
    require_chip()
    pipeline.export(corexy_run)
    scn = load_scenario_of(corexy_run)
    cfg = replace(default_machine(scn), sample_hz=1000)
    if shaper != "none":
        cfg = replace(cfg, shaper=shaper, shaper_taps=shaper_taps(shaper, {"f_hz": (40.0, 40.0), "zeta": (0.1, 0.1)}, 1000))
    lib = export_arduino(corexy_run, tmp_path / "lib", cfg)
    features, left, flash = uno_features(tmp_path / "lib", lib["name"], cfg)
    assert 0 < flash <= chip.MCUS["atmega328p"].flash_bytes
    assert features == frozenset(cfg.features) - set(left)
    # every smaller loss in DROPS's order does not fit
    for drop in DROPS[:DROPS.index(tuple(sorted(left, key=DROPS[-1].index)))]:
        c = replace(cfg, features=frozenset(cfg.features) - set(drop))
        with pytest.raises(TargetError, match="does not fit"):
            chip.build_sketch(tmp_path / "lib", f"{lib['name']}_gcode", tmp_path / f"b{len(drop)}", c.defines())
    # the Mega's build from the library's own header carries every option and fits
    fw = chip.build_sketch(tmp_path / "lib", f"{lib['name']}_gcode", tmp_path / "mega", mcu="atmega2560")
    assert fw.flash_bytes <= chip.MCUS["atmega2560"].flash_bytes
    header = (tmp_path / "lib" / "src" / "nnik_gcode_config.h").read_text()
    assert all(f"NNIK_GC_{f.upper()} 1  /*" in header for f in FEATURES)
