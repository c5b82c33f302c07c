"""A command's texts in one record, and the one way a command module adds its commands to a parser.

Each command module states its commands as :class:`Command` records (the name, the one
line its group lists, the description of its ``--help`` and its exit statuses) and adds
each with :meth:`Command.add`, which also names the handler; the options are the module's.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import NamedTuple

Handler = Callable[[argparse.Namespace], int]


class Command(NamedTuple):
    """A subcommand as ``--help`` shows it: its name, one line of help, its description and its epilog."""

    name: str
    help: str
    description: str
    epilog: str | None = None

    def add(self, subparsers: argparse._SubParsersAction, handler: Handler) -> argparse.ArgumentParser:
        """This command's parser in ``subparsers``, run by ``handler``; the caller adds its options."""
        parser = subparsers.add_parser(self.name, help=self.help, description=self.description, epilog=self.epilog)
        parser.set_defaults(handler=handler)
        return parser
