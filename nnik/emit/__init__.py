"""What every C generator of nnik shares (each family's own generator lives in its folder under
nnik/implementations/):

templating: the one jinja2 environment, the codegen/ folders, writing NAME.{c,h} with the runtime
headers; c_text: C comment and identifier helpers; avr_asm: the asm statement every AVR fast path
(the MLP kernel, lut, hybrid) is built on.

This package imports nothing on import, so that any module may import one generator alone.
"""
