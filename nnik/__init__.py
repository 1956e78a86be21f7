"""nnik: inverse kinematics of small motion machines as verified fixed-point C for 8-bit MCUs."""

__version__ = "0.1.0"
