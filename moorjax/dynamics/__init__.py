"""Time-domain dynamics: the ODE on line states and the diffrax driver."""

from .simulate import SimulationResult as SimulationResult
from .simulate import simulate as simulate
from .simulate import timed_simulate as timed_simulate
from .solvers import SOLVERS as SOLVERS
from .solvers import make_solver as make_solver
