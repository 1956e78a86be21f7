;FLAVOR:Marlin
;Generated in the layout of Cura/PrusaSlicer: only the XY moves, E words left out
; nnik-machine: tool=pen pen_z_um=250
;a pen plotter's Z: 0.2 mm draws, a 0.6 mm hop travels
N1 G21*27
N2 G90*18
;LAYER:0
N3 G0 F3000 X-5 Y-5 Z0.6*28
N4 G1 F1000 Z0.2*29
;TYPE:WALL-OUTER
N5 G1 F1800 X5 Y-5*110
N6 G1 X5 Y5*47
N7 G1 X-5 Y5*3
N8 G1 X-5 Y-5*33
N9 G0 F3000 Z0.6*23
N10 G0 X-3 Y-3*25
N11 G1 F1000 Z0.2*41
;TYPE:FILL
N12 G1 F2400 X3 Y-3*87
N13 G1 X3 Y-2*55
N14 G1 X-3 Y-2*29
N15 G1 X-3 Y-1*31
N16 G1 X3 Y-1*49
N17 G0 F3000 Z0.6*40
N18 G0 X0 Y0*17
N19 M400*31
