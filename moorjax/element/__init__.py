"""Line discretisations (element types) and their mass treatments."""

from .base import AbstractElement as AbstractElement
from .hermite import HermiteElement as HermiteElement
from .linear import LinearElement as LinearElement
from .mass import AbstractMass as AbstractMass
from .mass import ConsistentMass as ConsistentMass
from .mass import NodalMass as NodalMass
