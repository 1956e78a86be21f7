"""Hand-edited JSON that nnik reads back (issue 25): pick.json and metrics.json that are valid JSON
with a wrong type inside (a traceback before) are one `nnik: error:` line naming the file and the
key, exit 2, nothing changed.  Every key the readers check is spoiled in turn, read from the
shapes themselves (nnik.files.json_shape), so a key added there is covered too."""

from __future__ import annotations

import json

import pytest

from nnik.files import json_shape as js
from tests.bad_input import fails
from tests.conftest import DATASETS
from tests.pick_fixtures import copy_picked, picked_run  # noqa: F401 (fixture)

JOBS = DATASETS / "jobs"


def wrong_value(shape):
    """A JSON value of a type the shape refuses."""
    alts = shape if isinstance(shape, tuple) else (shape,)
    for v in ("x", 7, [1], {"a": 1}, True):
        if not any(js._fits(v, s) for s in alts):
            return v
    raise AssertionError(shape)


def spoilable(doc, shape, path=()):
    """(key path, the shape there) of every key in doc that the shape checks."""
    if isinstance(shape, dict) and isinstance(doc, dict):
        for key, sub in shape.items():
            k = key.lstrip("?")
            if k in doc:
                yield (*path, k), sub
                yield from spoilable(doc[k], sub, (*path, k))
    elif isinstance(shape, list) and isinstance(doc, list) and doc:
        yield (*path, 0), shape[0]
        yield from spoilable(doc[0], shape[0], (*path, 0))
    elif isinstance(shape, tuple) and doc is not None:
        inner = next((s for s in shape if isinstance(s, (dict, list)) and js._fits(doc, s)), None)
        if inner is not None:
            yield from spoilable(doc, inner, path)


def spoil(doc, path, value):
    doc = json.loads(json.dumps(doc))
    d = doc
    for k in path[:-1]:
        d = d[k]
    d[path[-1]] = value
    return doc


def dotted(path) -> str:
    out = ""
    for k in path:
        out += f"[{k}]" if isinstance(k, int) else (f".{k}" if out else k)
    return out


@pytest.fixture(scope="module")
def run(picked_run, tmp_path_factory):
    return copy_picked(picked_run, tmp_path_factory.mktemp("json") / "run")


def spoil_each_key(capsys, run, name: str, shape, argvs, at_least: int) -> None:
    """Each key the shape checks given a wrong type in turn: every command is one line naming it."""
    f = run / name
    good = f.read_text()
    cases = list(spoilable(json.loads(good), shape))
    assert len(cases) > at_least
    try:
        for path, sub in cases:
            f.write_text(json.dumps(spoil(json.loads(good), path, wrong_value(sub))))
            for argv in argvs:
                fails(capsys, argv, name, f"{dotted(path)}: expected", watch=run)
    finally:
        f.write_text(good)


def test_every_key_of_pick_json_with_a_wrong_type_is_one_line(run, capsys):
    spoil_each_key(capsys, run, "pick.json", js.PICK, (["verify", run], ["job", run, "missing.gcode", "--no-chip"]), 20)


def test_every_key_of_metrics_json_with_a_wrong_type_is_one_line(run, capsys):
    spoil_each_key(capsys, run, "metrics.json", js.METRICS, (["export", run],), 40)


def test_a_recorded_configuration_that_cannot_be_refitted_is_one_line(run, capsys):
    f = run / "pick.json"
    good = f.read_text()
    m = json.loads(good)
    try:
        f.write_text(json.dumps({**m, "config": {k: "x" for k in m["config"]}}))
        fails(capsys, ["job", run, JOBS / "l_path.gcode", "--no-chip"], "pick.json's", "configuration", "cannot be refitted")
    finally:
        f.write_text(good)
