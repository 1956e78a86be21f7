"""What gets flashed is what was verified: c/NAME.c against the hash of the C that ran, and the
completion marker pick.json (nnik.files.pick_state), seen from verify, job, export --arduino and report."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from nnik.files import pick_state
from nnik.files.c_hash import dir_hash
from nnik.cli import main
from nnik.report import load_metrics, summary_rows
from tests.bad_input import fails
from tests.conftest import DATASETS
from tests.pick_fixtures import copy_picked, picked_run  # noqa: F401 (fixture)

NAME = "galvo_cba2012"
L_PATH = DATASETS / "jobs" / "l_path.gcode"


def deliveries(run: Path, lib: Path) -> list[list]:
    return [["job", run, L_PATH, "--no-chip"], ["export", run, "--arduino", lib]]


def test_edited_pick_is_shown_and_refused_as_not_verified(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    verified = pick_state.status(run).verified_hash
    c = run / "c" / f"{NAME}.c"
    text = c.read_text()
    assert text.count("out[1] = ") >= 1
    c.write_text(text.replace("out[1] = ", "out[1] = 1 + "))  # every call now answers one step off
    on_disk = dir_hash(run / "c", NAME)
    st = pick_state.status(run)
    assert (st.ok, st.state, st.disk_hash, st.verified_hash) == (False, "changed", on_disk, verified)
    lib = tmp_path / "lib"
    for argv in deliveries(run, lib):
        fails(capsys, argv, on_disk, verified, f"nnik verify {run} --target avr", f"nnik select {run}")
    assert not lib.exists()
    # nnik verify runs the bytes on disk, not the MLP: one line, exit 2, nothing recorded
    line = fails(capsys, ["verify", run], "mismatches on host", "nnik select")
    assert line.count("nnik: error") == 1
    assert pick_state.status(run).state == "changed"
    # the report keeps the pick's name but none of its figures, and says why
    m = load_metrics(run)
    assert m["pick_status"]["state"] == "changed"
    row = next(r for r in m["selection"]["implementations"] if r["picked"])
    assert row["cycles"] == {"avr": None, "pic18": None} and "not_run" in row["host"]
    summary = "\n".join(" | ".join(r) for r in summary_rows(m))
    assert "NOT verified" in summary and on_disk in summary and verified in summary
    assert main(["report", str(run)]) == 0
    md = (run / "report" / "report.md").read_text()
    assert f"The pick (lut) is NOT verified" in md or "is NOT verified" in md
    assert on_disk in md and verified in md and f"nnik verify {run} --target avr" in md


def test_reverified_bytes_become_the_pick(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    c = run / "c" / f"{NAME}.c"
    c.write_text(c.read_text() + "/* reviewed by hand */\n")  # same behaviour, other bytes
    lib = tmp_path / "lib"
    fails(capsys, ["export", run, "--arduino", lib], "is NOT the C that was verified")
    assert main(["verify", str(run)]) == 0  # host only: not enough to flash
    st = pick_state.status(run)
    assert st.state == "unverified" and "has not been verified on avr" in st.message
    assert st.check("host")["bit_exact"] and st.check("host")["c_hash"] == dir_hash(run / "c", NAME)
    fails(capsys, ["export", run, "--arduino", lib], f"nnik verify {run} --target avr")
    assert main(["verify", str(run), "--target", "avr"]) == 0
    st = pick_state.status(run)
    assert st.ok and st.verified_hash == st.disk_hash == dir_hash(run / "c", NAME)
    capsys.readouterr()
    assert main(["export", str(run), "--arduino", str(lib)]) == 0
    assert (lib / "src" / f"{NAME}.c").read_bytes() == c.read_bytes()
    # the library's url comes from pyproject's [project.urls] Homepage, empty while there is none
    from nnik.firmware.arduino import homepage

    props = dict(ln.split("=", 1) for ln in (lib / "library.properties").read_text().splitlines())
    assert props["url"] == homepage() and "github.com/nnik" not in (lib / "library.properties").read_text()
    row = next(r for r in load_metrics(run)["selection"]["implementations"] if r["picked"])
    assert row["cycles"]["avr"] == st.check("avr")["cycles"] and row["host"]["c_hash"] == st.disk_hash


def test_verify_a_family_on_request(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    assert main(["verify", str(run), "--family", "poly"]) == 0
    assert f"c/alt/poly/{NAME}.c" in capsys.readouterr().out
    alt = run / "c" / "alt" / "poly" / f"{NAME}.c"
    alt.write_text(alt.read_text().replace("out[0] = ", "out[0] = 2 + "))
    fails(capsys, ["verify", run, "--family", "poly"], f"c/alt/poly/{NAME}.c", "mismatches on host")
    assert pick_state.status(run).ok  # the pick itself is untouched


@pytest.mark.parametrize("spoil", ["no marker", "corrupt marker", "other model", "evaluate another model", "metrics rewritten"])
def test_no_finished_pick_nothing_is_delivered(picked_run, tmp_path, capsys, spoil):
    run = copy_picked(picked_run, tmp_path / "run")
    marker = run / pick_state.PICK_FILE
    if spoil == "no marker":
        marker.unlink()
    elif spoil == "corrupt marker":
        marker.write_text(marker.read_text()[:40])
    elif spoil == "other model":
        (run / "data.npz").write_bytes((run / "data.npz").read_bytes() + b"\0")
    elif spoil == "evaluate another model":
        import torch

        from nnik.implementations.mlp.train import TrainedModel

        model = TrainedModel.load(run / "model.pt")
        with torch.no_grad():  # another model.pt than the pick was made from (evaluating the
            next(model.net.parameters()).view(-1)[0] += 1e-9  # same one keeps the pick: test_bad_input_dataloss.py)
        model.save(run / "model.pt")
        assert main(["evaluate", str(run)]) == 0  # metrics.json rewritten without the selection
        assert not marker.exists()
    else:
        m = json.loads((run / "metrics.json").read_text())
        m["selection"]["pick"]["family"] = "poly"
        (run / "metrics.json").write_text(json.dumps(m))
    assert (run / "c" / f"{NAME}.c").is_file()  # the C is there, but nothing says it was finished
    lib = tmp_path / "lib"
    for argv in deliveries(run, lib):
        fails(capsys, argv, f"nnik select {run}")
    assert not lib.exists()
    fails(capsys, ["verify", run], f"nnik select {run}")


def test_pick_in_other_input_units_is_not_firmware(picked_run, tmp_path, capsys):
    run = copy_picked(picked_run, tmp_path / "run")
    marker = run / pick_state.PICK_FILE
    m = json.loads(marker.read_text())
    marker.write_text(json.dumps({**m, "input_unit_um": 0.25}))
    assert pick_state.status(run).ok
    fails(capsys, ["job", run, L_PATH, "--no-chip"], "units of 0.25 um", "whole micrometres")


def test_select_that_dies_before_its_marker_delivers_nothing(picked_run, tmp_path, capsys, monkeypatch):
    """The last stage of a selection: c/NAME.c, c/alt/ and metrics.json written, pick.json not."""
    from nnik import pipeline

    run = copy_picked(picked_run, tmp_path / "run")

    def crash(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(pick_state, "seal", crash)
    with pytest.raises(KeyboardInterrupt):
        pipeline.select(run, progress=False, families=["poly"])
    assert load_metrics(run)["selection"]["pick"]["family"] == "poly"
    assert dir_hash(run / "c", NAME) == dir_hash(run / "c" / "alt" / "poly", NAME)
    st = pick_state.status(run)
    assert st.state == "none" and f"c/{NAME}.c is not a finished pick" in st.message
    for argv in deliveries(run, tmp_path / "lib"):
        fails(capsys, argv, "did not finish", f"nnik select {run}")
