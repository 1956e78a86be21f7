; Seed 001's step sequence: 25 mm on X, 20 mm on Y, then both back to the corner at once (a
; diagonal step), each held 2 s (;@step, docs/closed_loop.md). Runs on a dc_servo xy_table only.
G21 G90
G4 P0.2
;@step X25
G4 P2
;@step Y20
G4 P2
;@step X0 Y0
G4 P2
