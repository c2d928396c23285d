"""Floating bodies: a rigid body (Cummins form), its hydrodynamics, waves and loads."""

from .coupling import attach as attach
from .coupling import mooring_wrenches as mooring_wrenches
from .rigid_body import DOF_NAMES as DOF_NAMES
from .rigid_body import RigidBody as RigidBody
from .rigid_body import rotation as rotation
from .hydro import HydroCoefficients as HydroCoefficients
from .hydro import RadiationStateSpace as RadiationStateSpace
from .hydro import fit_radiation as fit_radiation
from .hydro import load_hydro as load_hydro
from .hydro import save_hydro as save_hydro
from .loads import ConstantLoad as ConstantLoad
from .loads import current_force as current_force
from .loads import directional_load as directional_load
from .loads import wind_force as wind_force
from .waves import IrregularWave as IrregularWave
from .waves import WaveLoads as WaveLoads
from .waves import pm_spectrum as pm_spectrum
from .waves import wave_components as wave_components
from .waves import wave_loads as wave_loads
from .point import ConnectionPoint as ConnectionPoint
from .submerged import SubmergedBody as SubmergedBody
