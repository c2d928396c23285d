"""Errors and warnings raised while reading moorjax input files.

Every message starts with ``<file>:<line>:`` (1-based line number) when a line
can be named, then says which field was wrong, the value as written (with its
unit) and what was expected, e.g.::

    case.dat:22: LINE TYPES 'main': Diam = -0.09 m must be > 0
"""

from __future__ import annotations


class InputError(ValueError):
    """A deck or motion file is malformed, inconsistent or uses an unsupported feature."""


class InputWarning(UserWarning):
    """Something in an input file is ignored or was given an assumed value."""
