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


def test_a_build_past_the_linkers_region_is_a_does_not_fit_and_the_export_says_so(corexy_run, tmp_path):
    """Past the Uno's 32 KiB the linker itself refuses (region text overflowed): that is 'does not
    fit' too, so the Uno fit tries the next choice and, when none fits, reports -1 (the export then
    warns that the build is for the Mega) instead of a traceback."""
    require_chip()
    pipeline.export(corexy_run)
    cfg = default_machine(load_scenario_of(corexy_run))
    lib = export_arduino(corexy_run, tmp_path / "lib", cfg)
    # 8 KiB of constant data the sketch keeps (a real link, made too big on purpose)
    (tmp_path / "lib" / "src" / "zz_ballast.c").write_text(
        "#include <avr/pgmspace.h>\n#include <stdint.h>\n"
        "const uint8_t zz_ballast[8192] PROGMEM = {1};\n"
        "uint8_t zz_touch(uint16_t i) { return pgm_read_byte(&zz_ballast[i]); }\n")
    ino = tmp_path / "lib" / "examples" / f"{lib['name']}_gcode" / f"{lib['name']}_gcode.ino"
    ino.write_text(ino.read_text() + "\nextern \"C\" uint8_t zz_touch(uint16_t i);\n"
                   "volatile uint8_t zz_sink;\nvoid zz_keep(void) { zz_sink = zz_touch(zz_sink); }\n"
                   "struct ZzKeep { ZzKeep() { zz_keep(); } } zz_keep_now;\n")
    with pytest.raises(TargetError, match=r"does not fit the atmega328p: flash over by \d+ B"):
        chip.build_sketch(tmp_path / "lib", f"{lib['name']}_gcode", tmp_path / "b", cfg.defines())
    features, left, flash = uno_features(tmp_path / "lib", lib["name"], cfg)
    assert (features, left, flash) == (frozenset(cfg.features), (), -1)
