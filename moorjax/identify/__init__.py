"""Parameter identification: fit scene parameters to measured tension histories.

- :func:`experiment` / :func:`load_experiment`: a scene with its motion and the
  measured tensions (channels ``L<id>_tension_a|b``), weights and a time window;
- :func:`fit`: free parameters (:class:`Free`: start, bounds), one or more
  experiments, an optax optimiser → :class:`FitResult` (fitted values, loss
  history, final gradient norm, Gauss–Newton covariance);
- :func:`loss_and_gradient`: the joint misfit and its exact gradient (reverse
  mode through statics and dynamics) for any named parameters;
- :func:`tension_histories` / :func:`simulation`: the differentiable forward model.
"""

from .covariance import gauss_newton_covariance as gauss_newton_covariance
from .experiment import Experiment as Experiment
from .experiment import experiment as experiment
from .experiment import load_experiment as load_experiment
from .experiment import read_target as read_target
from .fit import FitResult as FitResult
from .fit import default_optimizer as default_optimizer
from .fit import fit as fit
from .free import Free as Free
from .objective import loss_and_gradient as loss_and_gradient
from .objective import misfit_and_gradient as misfit_and_gradient
from .response import Simulation as Simulation
from .response import simulation as simulation
from .response import tension_histories as tension_histories
