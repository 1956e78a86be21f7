; Seed 001's step test on Y: the reference steps 20 mm at once (;@step, docs/closed_loop.md) from
; the homing corner, then holds 3 s. Runs on a dc_servo xy_table only.
G21 G90
G4 P0.2
;@step Y20
G4 P3
