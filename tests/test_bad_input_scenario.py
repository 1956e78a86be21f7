"""Scenario values that used to crash or fail late (issue 11, section 3-4): each is one line and
exit 2 from `nnik generate`, before any file is written."""

from __future__ import annotations

import pytest

from tests.bad_input import COREXY, GALVO, fails
from tests.conftest import DATASETS, write_toml


def _generate_fails(tmp_path, capsys, text, *needles):
    toml = write_toml(tmp_path, text)
    out = tmp_path / "out"
    fails(capsys, ["generate", toml, "-o", out], str(toml), *needles, watch=out)
    assert not out.exists()


@pytest.mark.parametrize("kind", ['["galvo_gimbal"]', '{ a = 1 }'])
def test_mechanism_kind_not_a_string(tmp_path, capsys, kind):
    _generate_fails(tmp_path, capsys, GALVO.replace('kind = "galvo_gimbal"', f"kind = {kind}"),
                    "[mechanism] kind", "must be one of")


def test_actuator_kind_not_a_string(tmp_path, capsys):
    _generate_fails(tmp_path, capsys, GALVO.replace('kind = "stepper"', 'kind = ["stepper"]'),
                    "[actuator] kind", "must be one of")


@pytest.mark.parametrize("key", ["n_train", "n_test"])
def test_point_counts_are_bounded(tmp_path, capsys, key):
    _generate_fails(tmp_path, capsys, GALVO.replace(f"{key} = ", f"{key} = 1000000000000 #"),
                    f"[dataset] {key}", "must be in [10, 2000000]")


def test_n_val_is_bounded(tmp_path, capsys):
    _generate_fails(tmp_path, capsys, GALVO.replace("seed = 0", "seed = 0\nn_val = 1000000000000"),
                    "[dataset] n_val", "2000000")


def test_seed_is_bounded(tmp_path, capsys):
    _generate_fails(tmp_path, capsys, GALVO.replace("seed = 0", f"seed = {2**62}"), "[dataset] seed", "4294967295")


def test_tiny_mm_per_rev(tmp_path, capsys):
    _generate_fails(tmp_path, capsys, COREXY.replace("mm_per_rev = 40.0", "mm_per_rev = 1e-9"),
                    "[workspace]", "int32 range", "mm_per_rev")


@pytest.mark.parametrize("hidden,needle", [("[100000]", "at most 256"), ("[6, 6, 6, 6, 6]", "at most 4 hidden layers")])
def test_network_size_is_bounded(tmp_path, capsys, hidden, needle):
    _generate_fails(tmp_path, capsys, GALVO.replace("hidden = [6]", f"hidden = {hidden}"), "[network] hidden", needle)


def test_training_memory_is_estimated_before_allocating(tmp_path, capsys):
    text = GALVO.replace("hidden = [6]", "hidden = [256, 256, 256, 256]").replace("n_train = 1000", "n_train = 2000000")
    _generate_fails(tmp_path, capsys, text, "[network] hidden", "GiB")


@pytest.mark.parametrize("name", ["NULL", "nnik_kernel", "NNIK_FLASH", "nnik", "int8_t", "main", "while", "_x", "sqrt"])
def test_names_that_collide_with_c(tmp_path, capsys, name):
    _generate_fails(tmp_path, capsys, GALVO.replace('name = "galvo_cba2012"', f'name = "{name}"'), "name", repr(name))


def test_name_too_long_for_sdcc(tmp_path, capsys):
    from nnik.emit.c_text import MAX_NAME_LEN

    name = "g" * (MAX_NAME_LEN + 1)
    _generate_fails(tmp_path, capsys, GALVO.replace('name = "galvo_cba2012"', f'name = "{name}"'),
                    "name", f"at most {MAX_NAME_LEN}")


def test_axes_near_parallel_rejected_before_training(tmp_path, capsys):
    """B_deg = 90 with A_deg = 90.25: the axes 0.25 deg apart used to fail only after training."""
    _generate_fails(tmp_path, capsys, COREXY.replace("B_deg = 0.15", "B_deg = 90.0"),
                    "[mechanism.distortion]", "near-singular", "within 45 deg of perpendicular")


@pytest.mark.parametrize("z", ["1.0", "1e-9"])
def test_gimbal_near_singularity(tmp_path, capsys, z):
    """z tiny: the beam grazes the plane. One line: no numpy divide-by-zero warning before it."""
    _generate_fails(tmp_path, capsys, GALVO.replace("z_mm = 300.0", f"z_mm = {z}"), "[mechanism] z_mm", "near-singular")


def test_galvo_dual_near_singularity(tmp_path, capsys):
    from tests.conftest import DATASETS

    text = (DATASETS / "galvo_dual_xy2.toml").read_text().replace("d_mm = 200.0", "d_mm = 0.5")
    _generate_fails(tmp_path, capsys, text, "[mechanism] d_mm", "near-singular")


@pytest.mark.parametrize("old,new,needle", [
    ("z_mm = 300.0", "z_mm = 1e300", "[mechanism] z_mm: must be in (0, 100000] mm"),
    ("x_mm = [-100.0, 100.0]", "x_mm = [-1e9, 100.0]", "[workspace] x_mm: must lie within +/-100000 mm"),
    ("microsteps = 16", "microsteps = 100000", "[actuator] microsteps: must be in [1, 1024]"),
])
def test_numbers_are_range_checked_before_any_work(tmp_path, capsys, old, new, needle):
    """Issue 15: what passes validation must compile and run; a huge number is one line, not a
    compiler error."""
    _generate_fails(tmp_path, capsys, GALVO.replace(old, new), needle)


HBOT = (DATASETS / "hbot_unicamp.toml").read_text()


@pytest.mark.parametrize("c_mm", ["400.0", "500.0"])
def test_hbot_carriage_wider_than_its_frame(tmp_path, capsys, c_mm):
    """Issue 25: an HBOT carriage as wide as its frame span, or wider, was accepted."""
    _generate_fails(tmp_path, capsys, HBOT.replace("C_mm = 60.0", f"C_mm = {c_mm}"), "[mechanism] C_mm",
                    "narrower than the frame span X_mm")


@pytest.mark.parametrize("motion, key", [
    ("junction_deviation_mm = 0", "junction_deviation_mm"),  # passed a whole run, then crashed export --arduino
    ("junction_deviation_mm = 2.0", "junction_deviation_mm"),
    ("max_feed_mm_min = 100000", "max_feed_mm_min"),  # above the firmware's 2^24 Q16 um/sample at 1 kHz
    ("accel_x_mm_s2 = 0.1", "accel_x_mm_s2"),  # below 16 Q16 um/sample^2 at 1 kHz
    ("sample_hz = 100", "accel_x_mm_s2"),  # the default 1000 mm/s^2 is beyond 2^22 Q16 um/sample^2 at 100 Hz
])
def test_motion_the_firmware_cannot_run(tmp_path, capsys, motion, key):
    _generate_fails(tmp_path, capsys, GALVO + f"\n[motion]\n{motion}\n", f"[motion] {key}", "must be in")


def test_input_unit_that_overflows_the_c_inputs(tmp_path, capsys):
    """A 3 m workspace in 0.001 um units is 3e9: beyond the C API's int32_t inputs."""
    text = COREXY.replace("[training]", "[export]\ninput_unit_um = 0.001\n\n[training]")
    text = text.replace("x_mm = [0.0, 200.0]", "x_mm = [0.0, 3000.0]")
    assert "x_mm = [0.0, 3000.0]" in text
    _generate_fails(tmp_path, capsys, text, "[export] input_unit_um", "int32")
