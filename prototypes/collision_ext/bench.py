"""Prototype vs numba: the same packed buffers and configurations through drake_mh's compiled
collision_free_packed (numba) and the C++ prototype; answers compared, ns per configuration
(median of interleaved rounds, wall and CPU).

Run: PYTHONPATH=<repo>:<folder with drake_mh_collision_ext> python prototypes/collision_ext/bench.py
"""
import time

import numpy as np

import drake_mh
from drake_mh.scene._entry_kernels import collision_free_packed
from drake_mh.scene.benchmark import benchmark_scene
from drake_mh.study.machine import cpu_model, load_average
from drake_mh_collision_ext import collision_free_packed as cpp


def main():
    robot = drake_mh.load_robot("panda")
    print(f"CPU: {cpu_model()}, load {load_average():.1f}")
    for kind in ("1 sphere", "10 mixed"):
        scene = benchmark_scene(robot, kind)
        model = scene.collision_model
        ints, floats = model.packed(scene.obstacle_arrays, model.no_pair_arrays)
        rng = np.random.default_rng(0)
        for N, rounds, calls in ((1024, 15, 20), (1, 15, 2000)):
            Q = np.ascontiguousarray(robot.random_configurations(max(N, 1024), rng=rng)[:N])
            out_n, out_c = np.empty(N, bool), np.empty(N, bool)
            assert collision_free_packed(Q, 1e-12, 1e-12, ints, floats, out_n)
            assert cpp(Q, 1e-12, 1e-12, ints, floats, out_c)
            QA = np.ascontiguousarray(robot.random_configurations(4096, rng=rng))
            a, b = np.empty(4096, bool), np.empty(4096, bool)
            collision_free_packed(QA, 0.01, 0.01, ints, floats, a)
            cpp(QA, 0.01, 0.01, ints, floats, b)
            assert np.array_equal(a, b), f"answers differ on {np.sum(a != b)} of 4096"
            times = {"numba": [], "C++": []}
            for _ in range(rounds):
                for name, f, out in (("numba", collision_free_packed, out_n), ("C++", cpp, out_c)):
                    w, c = time.perf_counter(), time.process_time()
                    for _ in range(calls):
                        f(Q, 1e-12, 1e-12, ints, floats, out)
                    times[name].append(((time.perf_counter() - w) / (calls * N), (time.process_time() - c) / (calls * N)))
            med = {k: (np.median([w for w, _ in v]) * 1e9, np.median([c for _, c in v]) * 1e9) for k, v in times.items()}
            print(f"{kind:9s} N={N:5d}: numba {med['numba'][0]:8.1f} ns/config (CPU {med['numba'][1]:8.1f}), "
                  f"C++ {med['C++'][0]:8.1f} (CPU {med['C++'][1]:8.1f}), numba/C++ {med['numba'][0] / med['C++'][0]:.2f}; "
                  f"free {np.mean(a):.2f} of 4096, same answers")


if __name__ == "__main__":
    main()
