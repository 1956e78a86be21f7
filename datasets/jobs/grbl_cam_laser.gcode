(issue 20's grbl-style CAM/laser job: N numbers, the modal header, G92, M3 S, lower case,)
(I/J arcs, M5, a dwell and M30; a 10 mm square with rounded corners and a circle)
N10 G17 G21 G90 G40 G49 G80
N20 G92 X0 Y0
N30 M3 S800
N40 g0 x5 y5
N50 G1 X-3 F1800
N60 G3 X-5 Y3 I0 J-2
N70 G1 Y-3
N80 G3 X-3 Y-5 I2 J0
N90 G1 X3
N100 G3 X5 Y-3 I0 J2
N110 G1 Y3
N120 G3 X3 Y5 I-2 J0
N130 G0 X2 Y0
N140 G2 X2 Y0 I-2 J0 F1200
N150 M5
N160 G4 P0.5
N170 G0 X0 Y0
N180 M30
