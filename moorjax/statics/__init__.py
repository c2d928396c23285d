"""Statics: the analytic elastic catenary and finite-element equilibrium."""

from .fem import LineStatics as LineStatics
from .fem import fairlead_stiffness as fairlead_stiffness
from .fem import initial_guess as initial_guess
from .fem import solve_line_statics as solve_line_statics
from .fem import solve_statics as solve_statics
from .system import SystemStatics as SystemStatics
from .system import mooring_stiffness as mooring_stiffness
from .system import offset_curve as offset_curve
from .system import solve_system_statics as solve_system_statics
from .system import system_stiffness as system_stiffness
