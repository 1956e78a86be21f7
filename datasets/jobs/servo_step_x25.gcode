; Seed 001's step test on X: the reference steps 25 mm at once (a raw step, not a planned move:
; the ;@step directive of closed-loop jobs, docs/closed_loop.md) from the homing corner, then holds
; 3 s for the loop to settle. Runs on a dc_servo xy_table only.
G21 G90
G4 P0.2
;@step X25
G4 P3
