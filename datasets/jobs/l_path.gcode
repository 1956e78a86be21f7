; Seed 003's test path: an L of two 10 mm legs, X then Y, from the work origin.
G21 G90 (mm, absolute)
G1 X10 Y0 F1200
G1 X10 Y10
M400
