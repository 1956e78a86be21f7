"""Kinematics, one small module per machine family, all behind the `Mechanism` interface."""

from nnik.machine.kinematics.base import Mechanism, Workspace
from nnik.machine.kinematics.corexy import CoreXY
from nnik.machine.kinematics.galvo_dual import GalvoDual
from nnik.machine.kinematics.galvo_gimbal import GalvoGimbal
from nnik.machine.kinematics.hbot import HBot
from nnik.machine.kinematics.measured import Measured
from nnik.machine.kinematics.xy_table import XYTable

KINDS: dict[str, type[Mechanism]] = {c.kind: c for c in (GalvoGimbal, GalvoDual, HBot, CoreXY, Measured, XYTable)}

__all__ = ["KINDS", "Mechanism", "Workspace"]
