import pytest

from drake_mh.errors import DrakeMhError, InvalidStudy
from drake_mh.study import Fields, Study
from drake_mh.study.spec import expand_grid


def _run(case):
    return {}


def test_dict_grid_is_cartesian_product_in_key_order():
    cases = expand_grid({"a": [1, 2], "b": ["x", "y", "z"]})
    assert len(cases) == 6
    assert cases[0] == {"a": 1, "b": "x"} and cases[-1] == {"a": 2, "b": "z"}


def test_list_grid_and_numpy_scalars():
    import numpy as np

    cases = expand_grid([{"a": np.int64(1)}, {"a": 2}])
    assert cases == [{"a": 1}, {"a": 2}] and type(cases[0]["a"]) is int


@pytest.mark.parametrize(
    "grid, words",
    [
        ({}, "empty"),
        ({"a": []}, "no cases"),
        ({"a": "abc"}, "list"),
        ({"a": [[1, 2]]}, "str, int, float or bool"),
        ([{"a": 1}, {"b": 2}], "keys"),
        ([{"a": 1}, {"a": 1}], "duplicate"),
        (42, "dict"),
    ],
)
def test_bad_grids_say_what_to_fix(grid, words):
    with pytest.raises(InvalidStudy, match=words):
        expand_grid(grid)


def test_study_validates_on_construction():
    with pytest.raises(InvalidStudy):
        Study(name="x", run=_run, grid={"a": []})
    with pytest.raises(InvalidStudy, match="seed"):
        Study(name="x", run=_run, grid={"a": [1]}, seed=-1)
    with pytest.raises(DrakeMhError, match="name"):
        Study(name="", run=_run, grid={"a": [1]})
    with pytest.raises(InvalidStudy, match="max_workers"):
        Study(name="x", run=_run, grid={"a": [1]}, max_workers=0)


def test_quick_grid_defaults_to_grid_and_instance_keys():
    study = Study(name="x", run=_run, grid={"robot": ["r"], "method": ["m", "n"], "rep": range(2)})
    assert study.cases(quick=True) == study.cases(quick=False)
    assert study.instance_keys() == ("robot", "rep")
    fields = Fields(instance=("robot",), rank=False)
    assert Fields.from_dict(fields.to_dict()) == fields


def test_study_is_frozen():
    study = Study(name="x", run=_run, grid={"a": [1]})
    with pytest.raises(AttributeError):
        study.seed = 3
