"""Floating bodies: a rigid body (Cummins form), its hydrodynamics, waves and loads."""

from .coupling import attach as attach
from .coupling import mooring_wrenches as mooring_wrenches
from .rigid_body import DOF_NAMES as DOF_NAMES
from .rigid_body import RigidBody as RigidBody
from .rigid_body import rotation as rotation
