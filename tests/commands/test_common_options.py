"""The options every command shares mean the same everywhere (nnik/commands/common_options.py).

Read from the parser itself, so a command or option added tomorrow is held to the same rules:
--quiet on every command, --json worded one way, -o naming a file or a directory, --target for
a chip (no --chip), --seed typed and worded one way; and --quiet and --json behave as they say.
"""

from __future__ import annotations

import argparse
import json

from hypothesis import given, settings, strategies as st

from nnik.cli import build_parser, main
from nnik.commands import common_options as co, option_types as opt
from tests.conftest import DATASETS


def commands() -> dict[str, argparse.ArgumentParser]:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def options(p: argparse.ArgumentParser):
    return [a for a in p._actions if a.option_strings]


def by_flag(p: argparse.ArgumentParser, flag: str):
    return next((a for a in options(p) if flag in a.option_strings), None)


def test_the_commands_are_there():
    assert set(commands()) >= {"run", "job", "select", "search", "verify", "report", "export", "generate", "train",
                               "evaluate", "estimate", "tanh", "synth-csv", "shaper-calibrate"}


def test_every_command_has_quiet_with_one_meaning():
    for name, p in commands().items():
        a = by_flag(p, "--quiet")
        assert a is not None, f"nnik {name} has no --quiet"
        assert a.help == co.QUIET_HELP and a.const is True and a.default is False, name


def test_json_means_the_same_where_it_is():
    having = [name for name, p in commands().items() if by_flag(p, "--json")]
    assert {"select", "verify", "estimate", "evaluate", "job"} <= set(having)
    for name in having:
        a = by_flag(commands()[name], "--json")
        assert a.help == co.JSON_HELP and a.const is True and a.default is False, name


def test_o_names_a_file_or_a_directory():
    seen = 0
    for name, p in commands().items():
        a = by_flag(p, "-o")
        if a is None:
            continue
        seen += 1
        assert a.option_strings == ["-o", "--outdir"] or a.option_strings == ["-o", "--output"], (name, a.option_strings)
        kind = "directory" if a.dest == "outdir" else "file"
        assert f"(a {kind}" in a.help, f"nnik {name} -o: its help must say it is a {kind}: {a.help!r}"
        assert a.metavar == ("DIR" if kind == "directory" else "FILE"), name
    assert seen >= 6


def test_no_chip_option_the_chip_is_target():
    for name, p in commands().items():
        for a in options(p):
            assert "--chip" not in a.option_strings, f"nnik {name} still has --chip (it is --target)"
            if "--target" in a.option_strings:
                assert a.choices and set(a.choices) <= {"host", *co.CHIPS}, name
    assert by_flag(commands()["select"], "--target").choices == co.CHIPS


def test_seed_is_typed_and_worded_one_way():
    having = [name for name, p in commands().items() if by_flag(p, "--seed")]
    assert having, "no command takes --seed"
    for name in having:
        a = by_flag(commands()[name], "--seed")
        assert a.type is opt.SEED, name
        assert a.help.startswith("seed of ") and "the same seed gives the same" in a.help, name
        assert f"default {a.default}" in a.help, name


def test_every_command_describes_itself():
    for name, p in commands().items():
        assert p.description and len(p.description) > 40, f"nnik {name}: give it a description"


def test_family_choices_are_the_registered_families():
    from nnik.implementations import FAMILIES

    for name in ("select", "verify"):
        assert by_flag(commands()[name], "--family").choices == tuple(FAMILIES)


@settings(max_examples=30, deadline=None)
@given(st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(),
                    lambda kids: st.lists(kids) | st.dictionaries(st.text(), kids), max_leaves=20))
def test_json_text_round_trips(value):
    assert json.loads(co.json_text(value)) == (value if value is not None else {})


def test_json_text_takes_numpy_and_paths():
    import numpy as np
    from pathlib import Path

    out = json.loads(co.json_text({"a": np.float64(1.5), "b": np.arange(3), "c": np.int64(7), "p": Path("x/y")}))
    assert out == {"a": 1.5, "b": [0, 1, 2], "c": 7, "p": "x/y"}


def test_quiet_prints_nothing_and_still_writes(tmp_path, capsys):
    """synth-csv --quiet: the CSV is written, stdout is empty; without it the same CSV and a line."""
    scn = DATASETS / "corexy_nonlinear.toml"
    assert main(["synth-csv", str(scn), "-o", str(tmp_path / "q.csv"), "-n", "30", "--quiet"]) == 0
    quiet = capsys.readouterr()
    assert quiet.out == "" and quiet.err == ""
    assert main(["synth-csv", str(scn), "-o", str(tmp_path / "l.csv"), "-n", "30"]) == 0
    assert "wrote" in capsys.readouterr().out
    assert (tmp_path / "q.csv").read_bytes() == (tmp_path / "l.csv").read_bytes()


def test_quiet_keeps_the_error_line(tmp_path, capsys):
    scn = DATASETS / "corexy_nonlinear.toml"
    assert main(["synth-csv", str(scn), "-o", str(tmp_path / "no" / "such" / "x.csv"), "-n", "30", "--quiet"]) == 2
    r = capsys.readouterr()
    assert r.out == "" and r.err.startswith("nnik: error: ") and len(r.err.strip().splitlines()) == 1
