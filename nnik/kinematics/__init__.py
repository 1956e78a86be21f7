"""Kinematics, one small module per machine family, all behind the `Mechanism` interface."""

from nnik.kinematics.base import Mechanism, Workspace
from nnik.kinematics.corexy import CoreXY
from nnik.kinematics.galvo_dual import GalvoDual
from nnik.kinematics.galvo_gimbal import GalvoGimbal
from nnik.kinematics.hbot import HBot
from nnik.kinematics.measured import Measured

KINDS: dict[str, type[Mechanism]] = {c.kind: c for c in (GalvoGimbal, GalvoDual, HBot, CoreXY, Measured)}

__all__ = ["KINDS", "Mechanism", "Workspace"]
