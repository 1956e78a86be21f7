"""The firmware's C, one file per concern: no two engine files that reach each other (the call graph
read from the objects by scripts/c_calls.py), the shared integer maths in nnik_imath.c alone,
nnik_gcode.c at most 600 lines, and every engine file in the Arduino library's export."""

from __future__ import annotations

import importlib.util
import subprocess
from pathlib import Path

import pytest

from nnik.firmware.arduino import ARDUINO, ENGINE_C, ENGINE_FILES
from tests.conftest import require_tool

ROOT = Path(__file__).resolve().parents[2]
SRC = ARDUINO / "src"
IMATH = ("nnik_isqrt32", "nnik_isqrt64", "nnik_div_round", "nnik_sq2", "nnik_mul_r")


def _c_calls():
    spec = importlib.util.spec_from_file_location("c_calls", ROOT / "scripts" / "c_calls.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def engine(tmp_path_factory):
    require_tool("gcc")
    require_tool("nm")
    c_calls = _c_calls()
    objects = c_calls.compile_engine(tmp_path_factory.mktemp("c_calls"))
    return c_calls, objects, c_calls.call_graph(objects)


def test_no_two_engine_files_reach_each_other(engine):
    c_calls, objects, graph = engine
    assert set(objects) == {p.name for p in c_calls.engine_files()}
    assert c_calls.circles(graph) == [], graph
    # the graph is read, not assumed: the edges every build has
    assert "nnik_imath.c" in graph["nnik_plan.c"] and "nnik_gc_parse.c" in graph["nnik_gcode.c"]
    assert "nnik_gcode.c" in graph["nnik_gc_read.c"] and "nnik_gc_read.c" in graph["nnik_gc_init.c"]


def test_the_integer_maths_has_one_home(engine):
    c_calls, objects, _ = engine
    for name, objs in objects.items():
        defined = set().union(*(c_calls.symbols(o)[0] for o in objs))
        if name == "nnik_imath.c":
            assert set(IMATH) <= defined
        else:
            assert not defined & set(IMATH) and not [s for s in defined if "sqrt" in s], (name, defined)


def test_the_check_finds_a_circle(tmp_path):
    """Two real files that call each other through a third are one circle; a file that only calls
    down is none."""
    require_tool("gcc")
    require_tool("nm")
    c_calls = _c_calls()
    texts = {"a.c": "int b1(int); int a1(int x) { return x ? b1(x - 1) : 0; }\n",
             "b.c": "int c1(int); int b1(int x) { return c1(x); }\n",
             "c.c": "int a1(int); int c1(int x) { return a1(x); }\n",
             "d.c": "int a1(int); int d1(void) { return a1(3); }\n"}
    objects = {}
    for name, text in texts.items():
        (tmp_path / name).write_text(text)
        subprocess.run(["gcc", "-O0", "-c", str(tmp_path / name), "-o", str(tmp_path / f"{name}.o")], check=True)
        objects[name] = [tmp_path / f"{name}.o"]
    graph = c_calls.call_graph(objects)
    assert graph == {"a.c": {"b.c"}, "b.c": {"c.c"}, "c.c": {"a.c"}, "d.c": {"a.c"}}
    assert c_calls.circles(graph) == [["a.c", "b.c", "c.c"]]
    assert c_calls.circles({"x": {"y"}, "y": set()}) == []


def test_the_interpreter_file_is_at_most_600_lines():
    n = len((SRC / "nnik_gcode.c").read_text().splitlines())
    assert n <= 600, n


def test_every_engine_file_is_exported():
    """The Arduino library (and the host build, which compiles ENGINE_C) carries every engine file of
    src/ (the closed loop's are exported by nnik.firmware.servo.export)."""
    files = _c_calls().engine_files(SRC, (".c", ".h"))
    assert set(ENGINE_FILES) == {p.name for p in files}
    assert set(ENGINE_C) | {"nnik_grbl.c"} == {p.name for p in files if p.suffix == ".c"}
