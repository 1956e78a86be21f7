"""Axis dynamics and vibration compensation: the belt as a base-excited spring-damper per axis
(seed 003), input shapers designed from (f, zeta) with Klipper's figures for each
(shaper_figures), offline precompensation, and calibration from Klipper's resonance test logs
(resonance_log, calibrate, calibrate_log; resonance_test simulates such a log).

Python decides here; the firmware's fixed-point shaper (codegen/arduino/src/nnik_shaper.c and its
model, the Shaper of nnik.firmware.gcode.planner) takes the constants that quantize() gives.
"""
