"""Show the Panda in Meshcat with an obstacle, a ghost and closest-point lines, play a 2-second
joint motion, and write it as a self-contained page ``panda_animation.html``.

Run::

    python examples/show_panda.py                 # prints the Meshcat URL, writes the page, exits
    python examples/show_panda.py --wait          # ... and keeps the live view open (Ctrl-C ends)
    python examples/show_panda.py --out /tmp/a.html

Open the URL (``http://localhost:7000``) while the script waits, or open the written page in
any browser, offline.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import drake_mh
import drake_mh.viz

Q_GOAL = np.array([0.481, 0.703, 0.093, -0.800, -0.364, 0.992, 0.026])
"""The ESM paper's initial configuration: flange at about (0.6, 0.3, 0.5) m."""


def minimum_jerk(q0: np.ndarray, q1: np.ndarray, duration: float, rate: float = 50.0):
    """Times ``t (K,)`` [s] and configurations ``Q (K, nq)`` of a rest-to-rest minimum-jerk motion."""
    t = np.linspace(0.0, duration, int(duration * rate) + 1)
    s = t / duration
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5
    return t, q0 + blend[:, None] * (q1 - q0)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="panda_animation.html", help="page to write")
    parser.add_argument("--wait", action="store_true", help="keep the live Meshcat view open until Ctrl-C")
    parser.add_argument("--quick", action="store_true", help="accepted for CI; the example is already quick")
    args = parser.parse_args(argv)

    robot = drake_mh.load_robot("panda")
    scene = drake_mh.Scene(robot)
    scene.add("ball", drake_mh.Sphere(0.08), position=[0.35, 0.35, 0.75])  # 4 cm from the motion

    q_start = robot.home
    t, Q = minimum_jerk(q_start, Q_GOAL, duration=2.0)

    view = drake_mh.viz.show(robot, (t, Q), scene=scene, target=robot.fk(Q_GOAL))
    view.add_ghost(Q_GOAL, "goal")
    pairs = view.add_distances(scene, Q_GOAL, max_pairs=5)
    print(f"live view: {view.url}")
    print(f"closest pair at the goal: {pairs[0].link} - {pairs[0].other}, {pairs[0].distance:.3f} m; "
          f"along the motion: {scene.exact_min_distance(Q).min():.3f} m")

    path = view.save_html(args.out)
    print(f"wrote {path} ({path.stat().st_size / 1e6:.2f} MB, opens offline)")
    if args.wait:
        print("Ctrl-C to stop the server")
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
