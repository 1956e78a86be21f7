"""hypothesis against grbl's reading rules (docs/gcode.md): comments, blanks, case, realtime and
high bytes, line length, checksums, numbers as exact decimals, and the last word of a modal group."""

from __future__ import annotations

from decimal import ROUND_DOWN, ROUND_HALF_UP, Decimal

from hypothesis import given, settings
from hypothesis import strategies as st

from nnik.firmware.gcode.codes import GcodeLineError
from nnik.firmware.gcode.parse import parse_block
from nnik.firmware.gcode.reader import EMPTY, ERROR, LINE, LINE_MAX, read_line, sendable

SET = settings(max_examples=300, deadline=None, database=None)
number = st.decimals(min_value=-99999, max_value=99999, allow_nan=False, allow_infinity=False, places=7)
word = st.builds(lambda letter, v: f"{letter}{v}", st.sampled_from("XYZIJFS"), number.map(lambda d: f"{d:f}"))
comment_text = st.text(alphabet=st.characters(min_codepoint=32, max_codepoint=126, blacklist_characters="()?!~"),
                       max_size=30)


def cleaned(text: str) -> str:
    return read_line(sendable(text.encode("utf-8"))).text


@SET
@given(words=st.lists(word, min_size=1, max_size=4), notes=st.lists(comment_text, min_size=5, max_size=5),
       tail=comment_text, blanks=st.sampled_from([" ", "\t", "  ", ""]))
def test_comments_blanks_and_case_change_nothing(words, notes, tail, blanks):
    plain = "".join(words)
    dressed = "".join(f"({notes[k % 5]}){blanks}{w.lower() if k % 2 else w}{blanks}" for k, w in enumerate(words))
    assert cleaned(dressed + f";{tail}") == cleaned(plain) == plain.upper()


@SET
@given(words=st.lists(word, min_size=1, max_size=4), junk=st.lists(st.sampled_from(["?", "!", "~", "\x18", "é", "\ufeff",
                                                                                      "/", "\x01"]), min_size=1, max_size=6),
       at=st.lists(st.integers(0, 200), min_size=6, max_size=6))
def test_realtime_and_high_bytes_and_block_delete_are_dropped_anywhere(words, junk, at):
    line = list("".join(words))
    for k, j in enumerate(junk):
        line.insert(at[k] % (len(line) + 1), j)
    assert cleaned("".join(line)) == "".join(words)


@SET
@given(n=st.integers(1, 120))
def test_79_characters_fit_and_80_are_error_11(n):
    rd = read_line(b"G1X" + b"1" * (n - 3) if n > 3 else b"G1X1"[:n])
    if n > LINE_MAX:
        assert rd.kind == ERROR and rd.code == 11
    else:
        assert rd.kind in (LINE, ERROR) and rd.code != 11


@SET
@given(body=st.lists(word, min_size=1, max_size=3).map(" ".join), n=st.integers(0, 9999), delta=st.integers(1, 255))
def test_checksums_are_the_xor_of_every_byte_before_the_star(body, n, delta):
    line = f"N{n} {body}"
    x = 0
    for c in line.encode():
        x ^= c
    assert read_line(f"{line}*{x}".encode()).kind == LINE
    assert read_line(f"{line}*{x} ; a comment".encode()).kind == LINE
    assert read_line(f"{line}*{x ^ delta}".encode()).code == 40


@SET
@given(value=number, inch=st.booleans())
def test_numbers_are_exact_decimals_rounded_half_away_from_zero(value, inch):
    text = f"{value:f}"
    b = parse_block(cleaned(f"X{text}"))
    cut = Decimal(text).copy_abs().quantize(Decimal("0.000001"), rounding=ROUND_DOWN)  # six decimals kept
    um = int((cut * (25400 if inch else 1000)).quantize(Decimal(1), rounding=ROUND_HALF_UP))
    um = min(um, 1 << 28)
    assert b.values["X"].to_um(inch) == (-um if value < 0 else um)


@SET
@given(codes=st.lists(st.sampled_from(["G0", "G1", "G2", "G3", "G80"]), min_size=1, max_size=5),
       units=st.lists(st.sampled_from(["G20", "G21"]), max_size=3))
def test_the_last_word_of_a_modal_group_wins(codes, units):
    b = parse_block("".join(codes + units))
    assert b.motion == {"G0": 0, "G1": 1, "G2": 2, "G3": 3, "G80": 80}[codes[-1]]
    assert b.inch == ({"G20": 1, "G21": 0}[units[-1]] if units else None)
    assert b.last_wins == len(codes) - 1 + max(len(units) - 1, 0)


@SET
@given(st.binary(max_size=120))
def test_any_bytes_get_an_answer_never_an_exception(data):
    rd = read_line(sendable(data.replace(b"\n", b"").replace(b"\r", b"")))
    assert rd.kind in (EMPTY, LINE, ERROR, "dollar")
    if rd.kind == LINE:
        try:
            parse_block(rd.text)
        except GcodeLineError as exc:
            assert 1 <= exc.code <= 43
