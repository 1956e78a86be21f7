"""Input files across every command (issue 25, part 6): missing, empty, a directory, binary, huge,
truncated and unreadable scenario TOMLs, G-code files and model directories are one
`nnik: error:` line and exit 2 with nothing written; LF, CRLF, CR alone and mixed line ends in a
scenario give the very same scenario."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from nnik.cli import main
from nnik.machine.scenario import load_scenario
from tests.bad_input import GALVO, copy_run, fails, tiny_run  # noqa: F401 (fixture)
from tests.conftest import DATASETS
from tests.pick_fixtures import picked_run  # noqa: F401 (fixture)

SCENARIO_COMMANDS = (["generate"], ["train"], ["run"], ["search"], ["synth-csv", "-o", "{tmp}/x.csv"])
UNREADABLE = Path("/proc/self/mem")  # a file whose read fails even for root (chmod 000 does not stop root)


def spoilt_inputs(tmp: Path) -> dict[str, tuple[Path, str]]:
    """{case: (path, what the line says)}."""
    text = GALVO
    cases = {"missing": (tmp / "none.toml", "not found"), "directory": (tmp, "a directory"),
             "empty": (tmp / "empty.toml", "missing required key"),
             "binary": (tmp / "bin.toml", "not a UTF-8 text file"),
             "truncated": (tmp / "trunc.toml", "malformed TOML"),
             "huge": (tmp / "huge.toml", "no scenario is that large")}
    cases["empty"][0].write_text("")
    cases["binary"][0].write_bytes(bytes(range(256)) * 4)
    cases["truncated"][0].write_text(text[: text.index("[actuator]") + 12])
    with open(cases["huge"][0], "w") as f:
        f.write(text + ("# padding\n" * (2 << 20)))
    if UNREADABLE.exists():
        cases["unreadable"] = (UNREADABLE, "cannot read")
    return cases


@pytest.mark.parametrize("command", SCENARIO_COMMANDS, ids=lambda c: c[0])
def test_bad_scenario_files_are_one_line(tmp_path, capsys, command):
    src = tmp_path / "in"
    src.mkdir()
    for case, (path, needle) in spoilt_inputs(src).items():
        out = tmp_path / "out"
        argv = [command[0], path, *[a.format(tmp=tmp_path) for a in command[1:]]]
        if command[0] != "synth-csv":
            argv += ["-o", out]
        if command[0] == "search" and case == "directory":
            needle = "no trained model"  # search takes a model directory too
        fails(capsys, argv, needle, watch=tmp_path / "in")
        assert not out.exists() and not (tmp_path / "x.csv").exists(), case


def test_gcode_job_files_are_one_line(picked_run, tmp_path, capsys):
    bad = {"missing": (tmp_path / "none.gcode", "not found"), "directory": (tmp_path, "a directory"),
           "empty": (tmp_path / "empty.gcode", "empty file"), "binary": (tmp_path / "bin.gcode", "binary data"),
           "nul": (tmp_path / "nul.gcode", "NUL byte")}
    bad["empty"][0].write_text("\n\n")
    bad["binary"][0].write_bytes(bytes(range(1, 32)) * 200)
    bad["nul"][0].write_bytes(b"G21\nG1 X1\0\n")
    if UNREADABLE.exists():
        bad["unreadable"] = (UNREADABLE, "cannot read")
    for case, (path, needle) in bad.items():
        fails(capsys, ["job", picked_run, path, "--check"], needle)


@pytest.mark.parametrize("ends", ["\r\n", "\r", "mixed"])
def test_line_ends_in_a_scenario_give_the_same_scenario(tmp_path, ends):
    lf = tmp_path / "lf.toml"
    lf.write_text(GALVO)
    lines = GALVO.split("\n")
    if ends == "mixed":
        text = "".join(ln + ("\r\n", "\r", "\n")[k % 3] for k, ln in enumerate(lines))
    else:
        text = ends.join(lines)
    f = tmp_path / "other.toml"
    f.write_bytes(text.encode())
    a, b = load_scenario(lf), load_scenario(f)
    assert a.raw == b.raw and a.fingerprint == b.fingerprint


MODEL_FILES = ("model.pt", "data.npz", "metrics.json")
# files a command does not need: evaluate writes metrics.json anew from the model and the data,
# estimate reads only the model and the data, and the report lists an unreadable model or data
# file as such in the report it writes
NOT_NEEDED = {("evaluate", "metrics.json"), ("estimate", "metrics.json"), ("report", "model.pt"), ("report", "data.npz")}
MODEL_COMMANDS = (["evaluate"], ["export"], ["select"], ["verify"], ["report"], ["estimate", "--target", "avr"])


@pytest.mark.parametrize("name", MODEL_FILES)
@pytest.mark.parametrize("spoil", ["truncated", "empty", "directory", "binary"])
def test_spoilt_files_in_a_model_directory_are_one_line(tiny_run, tmp_path, capsys, name, spoil):
    for command in MODEL_COMMANDS:
        run = copy_run(tiny_run, tmp_path / f"run-{command[0]}")
        f = run / name
        if spoil == "truncated":
            with open(f, "r+b") as fh:
                fh.truncate(os.path.getsize(f) // 2)
        elif spoil == "empty":
            f.write_bytes(b"")
        elif spoil == "binary":
            f.write_bytes(bytes(range(256)) * 8)
        else:
            f.unlink()
            f.mkdir()
        rc = main([command[0], str(run), *command[1:]])
        err = capsys.readouterr().err.strip().splitlines()
        if rc == 0:
            assert (command[0], name) in NOT_NEEDED, (command, name, spoil, err)
            continue
        assert rc == 2 and len(err) == 1 and err[0].startswith("nnik: error: "), (command, name, spoil, err)


def test_shipped_scenarios_still_load():
    for p in sorted(DATASETS.glob("*.toml")):
        load_scenario(p)


@pytest.mark.parametrize("ends", ["\r\n", "\r", "mixed"])
def test_line_ends_in_a_measured_csv_give_the_same_marks(tmp_path, ends):
    import numpy as np

    text = (DATASETS / "corexy_measured.csv").read_bytes().decode().replace("\r\n", "\n")
    lines = [ln for ln in text.split("\n") if ln]
    toml = (DATASETS / "corexy_measured.toml").read_text()
    out = {}
    for name, end in (("lf", "\n"), ("other", ends)):
        body = "".join(ln + ("\r\n", "\r", "\n")[k % 3] for k, ln in enumerate(lines)) if end == "mixed" \
            else end.join(lines) + end
        (tmp_path / f"{name}.csv").write_bytes(body.encode())
        (tmp_path / f"{name}.toml").write_text(toml.replace("corexy_measured.csv", f"{name}.csv"))
        m = load_scenario(tmp_path / f"{name}.toml").mechanism
        out[name] = (np.asarray(m.positions_mm), np.asarray(m.commands))
    assert len(out["lf"][0]) == len(lines) - 1
    assert all(np.array_equal(a, b) for a, b in zip(out["lf"], out["other"]))
