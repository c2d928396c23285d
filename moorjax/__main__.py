"""``python -m moorjax``: the command line (see :mod:`moorjax.cli`)."""

from .cli import run

run()
