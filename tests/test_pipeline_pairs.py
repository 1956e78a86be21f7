"""data.npz, model.pt and the scenario must belong together at every step."""

from __future__ import annotations

from tests.bad_input import COREXY, GALVO, copy_run, fails, tiny_run, with_training  # noqa: F401 (fixture)
from nnik.cli import main


def test_train_refuses_another_scenarios_data(tmp_path, capsys):
    g = tmp_path / "g.toml"
    g.write_text(with_training(GALVO.replace("n_test = 20000", "n_test = 300")))
    c = tmp_path / "c.toml"
    c.write_text(with_training(COREXY))
    out = tmp_path / "out"
    assert main(["generate", str(g), "-o", str(out)]) == 0
    fails(capsys, ["train", c, "-o", out], "data.npz was generated from scenario 'galvo_cba2012'",
          "not from the scenario 'corexy_nonlinear'", watch=out)


def test_train_refuses_data_of_an_edited_scenario(tmp_path, capsys):
    g = tmp_path / "g.toml"
    g.write_text(with_training(GALVO.replace("n_test = 20000", "n_test = 300")))
    out = tmp_path / "out"
    assert main(["generate", str(g), "-o", str(out)]) == 0
    g.write_text(g.read_text().replace("z_mm = 300.0", "z_mm = 310.0"))
    fails(capsys, ["train", g, "-o", out], "another version of it", watch=out)


def test_export_refuses_a_model_paired_with_other_data(tiny_run, tmp_path, capsys):
    run = copy_run(tiny_run, tmp_path / "run")
    c = tmp_path / "c.toml"
    c.write_text(with_training(COREXY))
    other = tmp_path / "other"
    assert main(["generate", str(c), "-o", str(other)]) == 0
    (run / "data.npz").write_bytes((other / "data.npz").read_bytes())
    fails(capsys, ["export", run], "data.npz was generated from scenario 'corexy_nonlinear'",
          "the model's scenario 'galvo_cba2012'", watch=run)
