"""Input and output at the edge: MoorDyn decks, motion files, scene building."""

from .build import body_reference_end as body_reference_end
from .build import build_scene as build_scene
from .build import coupled_body_ids as coupled_body_ids
from .build import coupled_point_ids as coupled_point_ids
from .build import read_deck_motion as read_deck_motion
from .dataset import to_dataset as to_dataset
from .deck import Deck as Deck
from .deck import parse_deck as parse_deck
from .deck import read_deck as read_deck
from .errors import InputError as InputError
from .errors import InputWarning as InputWarning
from .motion import Motion as Motion
from .motion import read_motion as read_motion
from .results import read_results as read_results
from .results import write_results as write_results
