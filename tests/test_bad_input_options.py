"""Option values across every command (issue 25, part 6), read from the parser itself so a new
option is covered the day it is added: every numeric option's type is a checked one
(nnik.commands.option_types), non-numeric, empty, infinite, NaN and overflowing values are one
`nnik: error:` line and exit 2 with nothing written, and negative, zero and huge values are either
refused the same way or accepted as this table says."""

from __future__ import annotations

import argparse

import pytest

from nnik.cli import build_parser
from nnik.commands import option_types as opt
from tests.bad_input import fails

# (command, option) -> which of -1, 0 and huge (1e300, or 10^30 for an integer option) it takes (the rest:
# one line, exit 2)
ACCEPTS = {
    ("run", "--search"): set(),
    ("select", "--max-error"): {"huge"},  # as [target] max_error: any positive limit
    ("select", "--max-cycles"): {"huge"},
    ("select", "--max-flash-bytes"): {"huge"},  # as [target] max_flash_bytes
    ("estimate", "--clock-hz"): set(),
    ("search", "--trials"): set(),
    ("search", "--jobs"): set(),
    ("synth-csv", "-n"): set(),
    ("synth-csv", "--noise-um"): {"0"},
    ("synth-csv", "--inset-mm"): set(),
    ("synth-csv", "--seed"): {"0"},
    ("job", "--scale"): set(),
    ("job", "--offset"): {"-1", "0"},
    ("job", "--tool-z"): {"-1", "0"},
    ("job", "--seg-um"): set(),
    ("excite", "--seconds"): set(),
    ("excite", "--seed"): {"0"},
    ("identify", "--supply"): set(),
}
SAMPLES = ("-1", "0", "huge")
ALWAYS_BAD = ("abc", "", "inf", "-inf", "nan", "1e400", "0x10", "1,5")


def commands() -> dict[str, argparse.ArgumentParser]:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def typed_options():
    """(command, flag, action) of every option that converts its value with a type."""
    for name, p in commands().items():
        for a in p._actions:
            if a.option_strings and a.type not in (None, str, opt.path):
                yield name, a.option_strings[-1] if a.option_strings[-1].startswith("--") else a.option_strings[0], a


def argv_with(command: str, flag: str, value: str, tmp_path) -> list[str]:
    """The command with its required arguments filled (a file under tmp_path) and flag=value."""
    p = commands()[command]
    argv = [command]
    for a in p._actions:
        if not a.option_strings and a.dest != "help":
            argv.append(str(tmp_path / a.dest))
        elif a.required and flag not in a.option_strings:
            argv += [a.option_strings[0], a.choices[0] if a.choices else str(tmp_path / a.dest)]
    return argv + [f"{flag}={value}"]


def test_every_typed_option_is_checked_and_in_the_table():
    seen = set()
    for name, flag, a in typed_options():
        assert isinstance(a.type, opt.Number) or a.type is opt.pair, \
            f"nnik {name} {flag}: give it a checked type from nnik/commands/option_types.py, not {a.type!r}"
        assert (name, flag) in ACCEPTS, f"nnik {name} {flag}: say in ACCEPTS which of -1, 0, huge it takes"
        seen.add((name, flag))
    assert seen == set(ACCEPTS), set(ACCEPTS) - seen


def _value(flag: str, v: str, kind: type = float) -> str:
    if v == "huge":
        v = "1" + "0" * 30 if kind is int else "1e300"
    return f"{v},0" if flag == "--offset" else v


def _kind(name: str, flag: str) -> type:
    a = next(a for n, f, a in typed_options() if (n, f) == (name, flag))
    return a.type.kind if isinstance(a.type, opt.Number) else float


@pytest.mark.parametrize("name, flag", sorted(ACCEPTS))
def test_non_numbers_infinities_and_nan_are_one_line(capsys, tmp_path, name, flag):
    for v in ALWAYS_BAD:
        if flag == "--offset" and v == "1,5":
            continue  # two numbers: X,Y
        fails(capsys, argv_with(name, flag, _value(flag, v), tmp_path), flag, watch=tmp_path)


@pytest.mark.parametrize("name, flag", sorted(ACCEPTS))
def test_negative_zero_and_huge_values(capsys, tmp_path, name, flag):
    p = commands()[name]
    for v in SAMPLES:
        argv = argv_with(name, flag, _value(flag, v, _kind(name, flag)), tmp_path)
        if v in ACCEPTS[(name, flag)]:
            p.parse_args(argv[1:])  # parsed; what the command does with it is its own test
        else:
            fails(capsys, argv, flag, "must be", watch=tmp_path)


def test_an_integer_option_refuses_a_fraction(capsys, tmp_path):
    for name, flag, a in typed_options():
        if isinstance(a.type, opt.Number) and a.type.kind is int:
            fails(capsys, argv_with(name, flag, "2.5", tmp_path), flag, "expected an integer")


def test_select_limits_are_judged_as_the_toml_judges_them(capsys, tmp_path):
    """The reported cases: --max-flash-bytes 0 and --max-error inf, refused as [target] refuses them."""
    line = fails(capsys, ["select", tmp_path, "--max-flash-bytes", "0"], "--max-flash-bytes", "must be > 0", watch=tmp_path)
    assert line.startswith("nnik: error: select: argument --max-flash-bytes")
    fails(capsys, ["select", tmp_path, "--max-error", "inf"], "--max-error", "finite", watch=tmp_path)
    fails(capsys, ["select", tmp_path, "--max-cycles", "-1"], "--max-cycles", "must be > 0", watch=tmp_path)


def test_argparse_complaints_are_one_line_too(capsys, tmp_path):
    fails(capsys, ["select"], "select", "required")
    fails(capsys, ["nosuchcommand"], "invalid choice")
    fails(capsys, ["verify", tmp_path, "--target", "z80"], "--target", "invalid choice")
    fails(capsys, ["synth-csv", tmp_path / "s.toml", "-o", tmp_path / "x.csv", "--seed", "-1"], "--seed", "must be in")


def path_arguments():
    for name, p in commands().items():
        for a in p._actions:
            if a.type is opt.path:
                yield name, a


def test_every_file_argument_refuses_an_empty_path(capsys, tmp_path):
    """`export --arduino ""` was accepted (and wrote nothing): every path argument refuses ''."""
    found = set()
    for name, a in path_arguments():
        argv = argv_with(name, "--", "", tmp_path)[:-1]  # the required arguments, then this one empty
        if a.option_strings:
            argv += [a.option_strings[-1], ""]
        else:
            k = [b.dest for b in commands()[name]._actions if not b.option_strings and b.dest != "help"].index(a.dest)
            argv[1 + k] = ""
        fails(capsys, argv, "needs a path", watch=tmp_path)
        found.add((name, a.dest))
    assert ("export", "arduino") in found and ("run", "outdir") in found and ("job", "job") in found


def test_no_path_argument_is_left_unchecked():
    for name, p in commands().items():
        for a in p._actions:
            if a.dest in opt.PATH_DESTS and not a.choices:
                assert a.type is opt.path, (name, a.dest)
