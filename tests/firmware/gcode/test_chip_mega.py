"""The library built for the Arduino Mega (ATmega2560, the core's mega variant) and run on
simavr's atmega2560: the self-test passes, and the G-code sketch builds within the Mega's limits."""

from __future__ import annotations

from nnik.firmware.arduino import export_arduino
from nnik.firmware.gcode import chip


def test_the_selftest_passes_on_the_mega(firmware, tmp_path):
    run, lib, _, _, _ = firmware["galvo_cba2012"]
    export_arduino(run, tmp_path / "lib")
    name = lib["name"]
    st = chip.build_sketch(tmp_path / "lib", f"{name}_selftest", tmp_path / "build", mcu="atmega2560")
    assert st.mcu == "atmega2560"
    res = chip.run_firmware(st, [], tmp_path / "build", 5.0)
    assert res.state == "halted"
    assert [t for _, t in res.replies][-1].startswith("PASS 64 vectors")
    fw = chip.build_sketch(tmp_path / "lib", f"{name}_gcode", tmp_path / "build", mcu="atmega2560")
    assert 0 < fw.flash_bytes <= chip.MCUS["atmega2560"].flash_bytes and 0 < fw.ram_bytes <= 8192 - 512
