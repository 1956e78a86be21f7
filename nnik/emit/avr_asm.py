"""The AVR asm builder every AVR fast path shares (the MLP kernel, the lut and hybrid families)."""

from __future__ import annotations


def asm_statement(lines: list[str], inputs: str, clobbers) -> list[str]:
    """One avr-gcc asm statement over an IK call's standard operands: the flag in r24, Z walking
    in_um, X walking out; ``inputs`` are the input operands (tables), ``clobbers`` the registers
    written. Shared by every AVR fast path (the MLP kernel, the lut and hybrid families)."""
    asm = "\n".join(f'        "{ln}\\n"' for ln in lines)
    clob = ", ".join(f'"{c}"' for c in clobbers)
    return [
        '    register int8_t flag __asm__("r24");',
        "    const int32_t *pin = in_um;",
        "    int32_t *pout = out;",
        "    __asm__ __volatile__ (",
        "        NNIK_AVR_ASM_MACROS",
        asm,
        "        NNIK_AVR_ASM_PURGE",
        '        : [flag] "=&r" (flag), "+z" (pin), "+x" (pout)',
        f"        : {inputs}",
        f"        : {clob});",
    ]
