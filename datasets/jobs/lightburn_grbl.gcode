; LightBurn 1.x, a GRBL device profile in its documented output layout
; Bounds: X-6 Y-4 to X6 Y4
G00 G17 G40 G21 G54
G90
M4
; Cut @ 1200 mm/min, 80% power
; M8 (air assist) is not sent: off in this profile
G0 X-6Y-4
; Layer C00
G1 X6S800F1200
G1 Y4
G1 X-6
G1 Y-4
G1 S0
G0 X-3Y0
; Layer C01
G1 X0Y3S400F2400
G1 X3Y0
G1 X0Y-3
G1 X-3Y0
G1 S0
M5
G90
; return to user-defined finish pos
G0 X0Y0
M2
