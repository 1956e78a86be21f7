; Seed 001's circle: a sine on X and a cosine on Y, amplitude 20 mm, mean 20 mm, period 125 s:
; x = 20 + 20 sin(2 pi t / 125), y = 20 + 20 cos(2 pi t / 125), so one clockwise turn about
; (20, 20) mm at 2 pi 20 mm / 125 s = 1.0053 mm/s = F60.32 mm/min, from (20, 40). It touches the
; strokes' edge X0 at t = 93.75 s. A planned move takes the table there from the homing corner.
G21 G90
G0 X20 Y40
G4 P1
G2 X20 Y40 I0 J-20 F60.32
G4 P1
