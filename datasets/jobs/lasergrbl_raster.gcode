; LaserGRBL-style raster engraving (its documented header, S on every G1 line, M4 for
; dynamic power, G0 between rows, M5 S0 at the end); the default footer's Z0 is left out:
; a laser without a Z axis refuses Z words
G90 (use absolute coordinates)
M4 S0
G0 X-5 Y-3 F3000
G1 X-4 S120 F1500
X-3 S400
X-2 S0
X-1 S1000
X1 S250
X3 S700
X5 S0
G0 Y-2
G1 X4 S300
X2 S900
X0 S0
X-2 S500
X-5 S150
G0 Y-1
G1 X-4 S1000
X5 S600
M5 S0
G0 X0 Y0 (move back to origin)
