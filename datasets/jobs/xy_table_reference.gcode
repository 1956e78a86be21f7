; The XY table's reference job: what `nnik run` tunes every controller on (the contour error, with
; limits on overshoot and duty) and picks the default by (the lowest RMS contour error). A raw step,
; then lines with corners and a full circle at 10 mm/s, about 9 s. Runs on a dc_servo xy_table only.
G21 G90
G4 P0.2
;@step X10 Y10
G4 P1
G1 X40 Y10 F600
G1 X40 Y30
G1 X20 Y30
G2 X20 Y30 I0 J-10
G1 X10 Y10
G4 P0.5
