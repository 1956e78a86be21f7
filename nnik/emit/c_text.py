"""User text that ends up in generated C: comments made safe, and the names C can take.

Every user-supplied string that a template prints (scenario paths, names, descriptions) goes
through :func:`c_comment_safe`; the scenario name, which prefixes every generated symbol, must
pass :func:`c_name_problem` before any work starts.
"""

from __future__ import annotations

import re

# The longest scenario name whose generated C still builds on every toolchain. SDCC pic16 names
# a function's code section "S_<file stem>__<function>" and gputils cuts section names at 78
# characters; two functions whose names then coincide fail in gpasm with "Each object file
# section must be contiguous". The tightest pair is NAME_float.c's NAME_float_round and
# NAME_float_ik: 2 + (n + 6) + 2 + (n + 7) + 1 <= 78, so n <= 30. Measured: 30 builds, 31 and
# 41 fail (tests/emit/test_c_text.py builds every generated file of a 30-character name on gpsim).
MAX_NAME_LEN = 30

C_KEYWORDS = frozenset("""
auto break case char const continue default do double else enum extern float for goto if inline
int long register restrict return short signed sizeof static struct switch typedef union unsigned
void volatile while _Bool _Complex _Imaginary _Alignas _Alignof _Atomic _Generic _Noreturn
_Static_assert _Thread_local asm typeof bool true false
""".split())

# Names the generated C, its harnesses and the C runtime already use, or that a C library defines.
C_RESERVED = frozenset("""
NULL main errno assert offsetof size_t ptrdiff_t wchar_t va_list EOF FILE stdin stdout stderr
int8_t int16_t int32_t int64_t uint8_t uint16_t uint32_t uint64_t intptr_t uintptr_t intmax_t uintmax_t
int_least8_t int_fast8_t INT8_MIN INT8_MAX INT16_MIN INT16_MAX INT32_MIN INT32_MAX INT64_MIN INT64_MAX
UINT8_MAX UINT16_MAX UINT32_MAX UINT64_MAX CHAR_BIT INT_MAX INT_MIN LONG_MAX LONG_MIN
abs labs div ldiv malloc calloc realloc free exit abort atoi atol strtol strtoul rand srand qsort bsearch
memcpy memmove memset memcmp strlen strcpy strncpy strcmp strncmp strcat strchr strrchr strstr
printf sprintf snprintf fprintf puts putchar getchar
sin cos tan asin acos atan atan2 sinh cosh tanh exp log log10 pow sqrt fabs floor ceil fmod
sinf cosf tanf asinf acosf atanf atan2f sinhf coshf tanhf expf logf log10f powf sqrtf fabsf floorf ceilf
fmodf round lround lroundf HUGE_VAL INFINITY NAN
ISR SREG TCNT1 PORTA PORTB TRISA TRISB WDTCON STKPTR
""".split())

_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


def c_name_problem(name: str) -> str | None:
    """Why `name` cannot prefix generated C symbols, or None if it can."""
    if not _IDENT.fullmatch(name):
        return f"must be a C identifier starting with a letter (letters, digits, _), got {name!r}"
    if len(name) > MAX_NAME_LEN:
        return (f"is {len(name)} characters; at most {MAX_NAME_LEN} fit the symbols SDCC/gputils "
                f"build for PIC18, got {name!r}")
    if name in C_KEYWORDS:
        return f"{name!r} is a C keyword"
    if name in C_RESERVED:
        return f"{name!r} is a name the C library, the runtime or the harness already defines"
    if name.lower() == "nnik" or name.lower().startswith("nnik_"):
        return f"{name!r} collides with the nnik runtime (names starting with nnik_ are reserved)"
    return None


_CTRL = re.compile(r"[\x00-\x1f\x7f]")


def c_comment_safe(text: object) -> str:
    """`text` made safe inside a C block comment, on one line, in ASCII.

    `*/` would end the comment and `/*` would nest; both are split by a space. Newlines and
    other control characters are shown as escapes, so a path cannot start a new line of code.
    Non-ASCII characters become \\uXXXX so every compiler reads the file (SDCC is picky).
    Backslashes are left alone: they cannot end a block comment.
    """
    s = str(text)
    s = _CTRL.sub(lambda m: f"\\x{ord(m.group()):02x}", s)
    s = "".join(c if ord(c) < 128 else f"\\u{ord(c):04x}" for c in s)
    while "*/" in s or "/*" in s:
        s = s.replace("*/", "* /").replace("/*", "/ *")
    return s
