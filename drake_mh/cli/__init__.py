"""The ``drake-mh`` command line (``python -m drake_mh``): it imports the library, the library
never imports it. :func:`main` runs it; :mod:`.main` builds the parser."""

from drake_mh.cli.main import (COMMAND_MODULES, PROG, UsageError, _smoke, add_robot_options, build_parser,
                               load_robot_from_args, main, register_robot_options, wants_progress)

__all__ = ["main", "build_parser", "PROG", "UsageError", "COMMAND_MODULES", "add_robot_options", "load_robot_from_args",
           "register_robot_options", "wants_progress"]
