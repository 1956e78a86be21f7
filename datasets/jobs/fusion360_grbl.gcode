(1001)
(Machine)
(  vendor: Autodesk)
(  description: Generic grbl, laser cutting as its grbl post writes 2D profiles)
(T1 D=0.1 CR=0 - ZMIN=0 - laser cutter)
G90 G94
G17
G21

(2D Profile1)
G0 X7 Y0
M3 S1000
G1 X7 Y0 F1000
G3 X0 Y7 I-7 J0
G3 X-7 Y0 I0 J-7
G3 X0 Y-7 I7 J0
G3 X7 Y0 I0 J7
M5
G0 X4 Y4
M3 S600
G1 X-4 F1500
G1 Y-4
G2 X4 Y-4 R4
G1 Y4
M5
G28 G91 X0 Y0
G90
M30
