; A circle of radius 8 mm about the work origin: four G3 quarter arcs (counter-clockwise),
; then the same circle once clockwise as one G2 whose end is its start.
G21 G90
G0 X8 Y0
G3 X0 Y8 I-8 J0 F1500
G3 X-8 Y0 I0 J-8
G3 X0 Y-8 I8 J0
G3 X8 Y0 I0 J8
G2 X8 Y0 I-8 J0
G0 X0 Y0
M400
