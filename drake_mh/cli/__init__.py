"""The ``drake-mh`` command line (``python -m drake_mh``), one module per command: it imports the
library, the library never imports it.

* :func:`main` runs it (the console script); :func:`build_parser` builds its parser
  (:mod:`.main`, with the commands in :data:`~.main.COMMANDS`);
* :func:`run_script`: a study script run by itself, as ``drake-mh study <that file>``;
* :mod:`.options` — what several commands share (robot options, progress bars).
"""

from drake_mh.cli.main import COMMAND_MODULES, COMMANDS, PROG, UsageError, build_parser, main, run_script
from drake_mh.cli.options import add_robot_options, load_robot_from_args, register_robot_options, wants_progress

__all__ = ["main", "build_parser", "run_script", "PROG", "UsageError", "COMMANDS", "COMMAND_MODULES",
           "add_robot_options", "load_robot_from_args", "register_robot_options", "wants_progress"]
