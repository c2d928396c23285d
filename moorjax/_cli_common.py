"""What every ``moorjax`` sub-command module shares: help layout, message
clipping and the ``example:NAME`` deck argument.

Kept apart from :mod:`moorjax.cli` so that sub-command modules
(:mod:`moorjax.identify.cli`, ...) need not import the command line that
imports them.
"""

from __future__ import annotations

import argparse
import re


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Keeps the epilog's layout and appends defaults that mean something."""

    def _get_help_string(self, action):
        text = action.help or ""
        if "%(default)" in text or "default" in text:
            return text
        if action.option_strings and not any(action.default is v for v in (None, False, True)) \
                and action.default != argparse.SUPPRESS:
            text += " (default: %(default)s)"
        return text


def clip(text: str, longest: int = 80) -> str:
    """``text`` with every token longer than ``longest`` characters shortened."""
    def short(m):
        tok = m.group(0)
        return f"{tok[:40]}…[{len(tok) - 50} more characters]…{tok[-10:]}"
    text = re.sub(rf"\S{{{longest + 1},}}", short, str(text))
    return text if len(text) <= 2000 else text[:2000] + f"… [{len(text) - 2000} more characters]"


def deck_path(arg: str) -> str:
    """The file of a DECK argument: ``example:NAME`` is a bundled deck, anything else a path."""
    if arg.startswith("example:"):
        from .examples import example_path

        return example_path(arg.split(":", 1)[1])
    return arg
