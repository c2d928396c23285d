"""Time-domain dynamics: the ODE on line and body states, and its one integrator.

- :mod:`~moorjax.dynamics.settings`: the validated settings (:func:`plan`);
- :mod:`~moorjax.dynamics.initial`: the start, :func:`equilibrium_state`;
- :mod:`~moorjax.dynamics.integrate`: ``integrate``, the one diffrax solve;
- :mod:`~moorjax.dynamics.adjoint`: how derivatives pass through it;
- :mod:`~moorjax.dynamics.simulate`: :func:`simulate`, all of these with checks.

This package is moorjax's only user of diffrax.
"""

from .initial import Equilibrium as Equilibrium
from .initial import equilibrium_state as equilibrium_state
from .integrate import SimulationResult as SimulationResult
from .settings import Settings as Settings
from .settings import plan as plan
from .simulate import simulate as simulate
from .simulate import timed_simulate as timed_simulate
from .solvers import SOLVERS as SOLVERS
from .solvers import make_solver as make_solver
