"""``python -m drake_mh [COMMAND ...]``: the ``drake-mh`` command line.

Without arguments it prints the robot catalogue with the FK/Jacobian/distance smoke test
and one line naming the commands (``python -m drake_mh demo`` runs the demo;
``python -m drake_mh --help`` prints the usage).
"""

import sys

from drake_mh.cli import main

if __name__ == "__main__":
    sys.exit(main())
