"""Ensembles: vmapped runs of many scenes of one structure, sharded and streamed."""

from .batch import StructureMismatchError as StructureMismatchError
from .batch import member as member
from .batch import stack as stack
from .devices import available_cores as available_cores
from .devices import use_cpu_cores as use_cpu_cores
from .run import equilibrium as equilibrium
from .run import simulate_ensemble as simulate_ensemble
from .run import status as status
