"""The framework paper's scenario (Table 3, obstacle (0.2, 0.2, 0.6) -> (0.1, 0.15, 0.4)) as a study case."""

import numpy as np
import pytest

from drake_mh.errors import InvalidArgument, UnknownMethod
from drake_mh.reactive.framework_scenario import PATH_EVENT, run_framework_scenario


def _check_record(rec, n_events):
    N = rec["n_points"]
    assert rec["traj_t"].shape == (N,) and rec["traj_q"].shape == (N, 6) and rec["plan_q"].shape == (N, 6)
    assert rec["obstacle_p"].shape == (N, 3) and rec["regenerated"].shape == (N,)
    assert rec["n_events"] == n_events and rec["event_index"].shape == (n_events,)
    assert np.allclose(rec["obstacle_p"][0], (0.2, 0.2, 0.6))
    assert np.allclose(rec["obstacle_p"][-1 if n_events == 1 else 10], (0.1, 0.15, 0.4))
    scalars = {k: v for k, v in rec.items() if not isinstance(v, np.ndarray)}
    assert all(isinstance(v, (bool, int, float, str)) for v in scalars.values())
    assert rec["points_regenerated"] == rec["regenerated"].sum() or n_events > 1


def test_scenario_regenerates_and_stays_clear():
    rec = run_framework_scenario("e3gsa", seed=0)  # measured: 16 of 48 points collide
    _check_record(rec, 1)
    assert rec["event1_colliding"] > 0 and rec["min_distance_unregenerated"] < 0   # the old plan would collide
    assert rec["success"] and rec["min_distance_executed"] >= 0.01 - 1e-9 and rec["min_distance_swept"] > 0
    assert rec["event1_regenerated"] == rec["event1_colliding"] == rec["regenerated"].sum()
    assert rec["max_step_executed"] < 0.5 and rec["max_position_error"] <= 1e-3


def test_scenario_is_deterministic():
    a = run_framework_scenario("pso", seed=1, budget=4000)
    b = run_framework_scenario("pso", seed=1, budget=4000)
    assert np.array_equal(a["traj_q"], b["traj_q"]) and a["points_regenerated"] == b["points_regenerated"]


@pytest.mark.slow
def test_scenario_with_the_path_event_replans_3nc_points():
    rec = run_framework_scenario("e3gsa", seed=1, path_event=PATH_EVENT)
    _check_record(rec, 2)
    assert rec["event2_path_colliding"] > 0 and rec["event2_replanned"] >= 2 * rec["event2_path_colliding"]
    assert rec["success"] and not np.allclose(rec["path_final"], rec["path_initial"])


def test_bad_arguments():
    with pytest.raises(UnknownMethod):
        run_framework_scenario("nope")
    with pytest.raises(InvalidArgument, match="move_at"):
        run_framework_scenario(move_at=60)
    with pytest.raises(InvalidArgument, match="path_event"):
        run_framework_scenario(path_event=(40, 30))
