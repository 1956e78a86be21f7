"""What avr-gcc really emits for a fast-kernel network's C path: the cycles of its straight-line
code, counted from the disassembly (avr-objdump -d -l of the model's object file) and attributed
to the source line (a kernel primitive, or a line of the generated C) each instruction came from.

At -O2 the C path of two hidden layers is straight-line code apart from the input clamp's branches
and the output shift's loop (when the output does not fold, e != 0), so this count is its cycle
count (tests/bench/mlp_cost/test_avr_static.py checks it against simavr); -Os rolls the constant
shifts into loops, counted here once.  A diagnostic for the cost
model: it prices each primitive as compiled, e.g. a layer-2 multiply-accumulate at about 25
cycles, where a fit that shares coefficients between code shapes may not.

    python3 -m nnik.bench.mlp_cost.avr_static OBJECT.o [SOURCE.c]
"""

from __future__ import annotations

import collections
import re
import subprocess
import sys
from pathlib import Path

# AVR (ATmega328P) cycles per instruction; branches and skips count as not taken (1)
CYCLES = {"mul": 2, "muls": 2, "mulsu": 2, "fmul": 2, "ldd": 2, "ld": 2, "lds": 2, "std": 2, "st": 2, "sts": 2,
          "lpm": 3, "elpm": 3, "push": 2, "pop": 2, "rcall": 3, "call": 4, "icall": 3, "ret": 4, "reti": 4,
          "rjmp": 2, "jmp": 3, "ijmp": 2, "adiw": 2, "sbiw": 2}
_INSN = re.compile(r"^\s+[0-9a-f]+:\s+(?:[0-9a-f]{2} )+\s+(\S+)")
_LINE = re.compile(r"^(/\S+):(\d+)")
_FUNC = re.compile(r"^[0-9a-f]+ <(.+)>:")


def static_cycles(obj: Path, function_suffix: str = "_ik") -> tuple[int, dict[str, int]]:
    """Cycles of the straight-line code of the function named *function_suffix in `obj`, and
    their split by source place ("file:line" of the primitive or generated line)."""
    asm = subprocess.run(["avr-objdump", "-d", "-l", str(obj)], capture_output=True, text=True, check=True).stdout
    by_place: collections.Counter[str] = collections.Counter()
    inside, place = False, "?"
    for line in asm.splitlines():
        m = _FUNC.match(line)
        if m:
            inside = m.group(1).endswith(function_suffix)
            continue
        m = _LINE.match(line)
        if m:
            place = f"{Path(m.group(1)).name}:{m.group(2)}"
            continue
        m = _INSN.match(line)
        if m and inside:
            by_place[place] += CYCLES.get(m.group(1), 1)
    return sum(by_place.values()), dict(by_place)


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if not args:
        print(__doc__.strip().splitlines()[-1].strip(), file=sys.stderr)
        return 2
    total, parts = static_cycles(Path(args[0]))
    src = Path(args[1]).read_text().splitlines() if len(args) > 1 else []
    for place, cyc in sorted(parts.items(), key=lambda kv: -kv[1]):
        name, _, ln = place.rpartition(":")
        text = src[int(ln) - 1].strip()[:70] if src and name.endswith(".c") and ln.isdigit() else ""
        print(f"{cyc:7d}  {place:28s} {text}")
    print(f"{total:7d}  total (straight line; loops once, branches not taken)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
