"""``python -m drake_mh.smoke``: the robot catalogue and smoke test, the same as ``drake-mh robots``
(the command lives in :mod:`drake_mh.cli.robots`; this name is kept for the shell)."""

import sys

if __name__ == "__main__":
    from drake_mh.cli import main

    sys.exit(main(["robots"]))
