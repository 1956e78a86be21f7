"""Every C generator of nnik, rendered through one jinja2 environment (templating.environment).

export: NAME.h / NAME.c of an MLP (the portable kernel's template, or fastc for the fast kernel);
fastc, fastc_avr, fastc_p18: the fast kernel's portable C, AVR asm and PIC18 asm bodies;
kernel: the fast kernel's numeric contract (tanh tables, shifts) that fastc and the quantiser share;
templating: the jinja2 environment and the codegen/ folders (templates, runtime headers).

This package imports nothing on import, so that any module may import one generator alone.
"""
