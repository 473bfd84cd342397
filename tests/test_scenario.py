"""Scenario files: loading, validation, the seeded generator."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
import yaml

from sensorless.exceptions import (
    FileFormatError,
    InputValueError,
    MissingFileError,
    ModelError,
    UnknownNameError,
)
from sensorless.io import read_log
from sensorless.simulation.plants import RigidPlant
from sensorless.simulation.scenario import (
    Scenario,
    available_scenarios,
    generate,
    load_scenario,
    lugre_from,
)


def test_shipped_scenarios_load() -> None:
    assert {"puma560-thesis", "panda-gaz"} <= set(available_scenarios())
    puma = load_scenario("puma560-thesis")
    assert puma.duration >= 60.0
    true, nominal = puma.robots()
    assert true.n_dof == nominal.n_dof == 6
    # 15 % model error on the nominal model, LuGre friction on the true robot.
    assert not np.allclose(true.parameter_vector(), nominal.parameter_vector())
    assert type(true.friction).__name__ == "LuGre"
    assert type(nominal.friction).__name__ == "CoulombViscous"
    parts = puma.build()
    assert isinstance(parts["plant"], RigidPlant)
    assert len(parts["contacts"]) == 9
    assert len(puma.build(collisions=False)["contacts"]) == 0
    # Table 5.1 in the built-in model's convention: the start pose is the "ready" pose.
    np.testing.assert_allclose(
        parts["trajectory"].evaluate(0.0)[0], np.deg2rad([0, 90, -90, 0, 0, 0]), atol=1e-12
    )
    panda = load_scenario("panda-gaz")
    true, nominal = panda.robots()
    assert (true.name, nominal.name) == ("panda_gaz", "panda")


def test_lugre_from_keeps_the_coulomb_viscous_steady_state() -> None:
    nominal = load_scenario("puma560-thesis").robots()[1].friction
    lugre = lugre_from(nominal, stiction_ratio=1.0)
    velocity = np.array([[0.5] * 6])
    expected = 0.5 * (np.abs(nominal.c_pos) + np.abs(nominal.c_neg)) + nominal.fv * 0.5
    np.testing.assert_allclose(lugre.steady_state(velocity)[0], expected, rtol=1e-12)


def test_model_error_is_fixed_by_its_own_seed_not_the_run_seed() -> None:
    scenario = load_scenario("puma560-thesis")
    first = scenario.build(seed=1)["controller"].model.parameter_vector()
    second = scenario.build(seed=2)["controller"].model.parameter_vector()
    np.testing.assert_array_equal(first, second)


def test_unknown_and_malformed_scenarios_give_clear_errors(tmp_path) -> None:
    with pytest.raises(UnknownNameError, match="puma560-thesis"):
        load_scenario("no-such-scenario")
    with pytest.raises(MissingFileError, match="scenario file not found"):
        load_scenario(tmp_path / "missing.yaml")
    spec = copy.deepcopy(load_scenario("panda-gaz").spec)
    spec["colisions"] = []
    path = tmp_path / "typo.yaml"
    path.write_text(yaml.safe_dump(spec))
    with pytest.raises(FileFormatError, match="colisions: unknown key; did you mean 'collisions'"):
        load_scenario(path)
    del spec["colisions"], spec["trajectory"]
    path.write_text(yaml.safe_dump(spec))
    with pytest.raises(FileFormatError, match="trajectory: required key is missing"):
        load_scenario(path)
    spec = copy.deepcopy(load_scenario("panda-gaz").spec)
    spec["trajectory"]["type"] = "spline"
    with pytest.raises(ModelError, match="unknown trajectory type 'spline'"):
        Scenario("bad", spec).build()
    for seconds in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(InputValueError, match="duration must be a positive, finite number"):
            load_scenario("panda-gaz").with_duration(seconds)


def test_generator_writes_free_and_collision_runs_with_disjoint_seeds(tmp_path) -> None:
    spec = copy.deepcopy(load_scenario("panda-gaz").spec)
    spec["duration"] = 2.5
    spec["random_collisions"] = {**spec["random_collisions"], "count": 1}
    paths = generate(Scenario("panda-small", spec), 2, master_seed=5, out_dir=tmp_path)
    assert [p.name for p in paths] == [
        "panda-small-free-000.parquet",
        "panda-small-free-001.parquet",
        "panda-small-collision-000.parquet",
        "panda-small-collision-001.parquet",
    ]
    logs = [read_log(p) for p in paths]
    seeds = [log.metadata["seed"] for log in logs]
    assert len(set(seeds)) == 4
    assert all(not log.collision_id.any() for log in logs[:2])
    assert all(log.collision_id.any() for log in logs[2:])
    again = generate(Scenario("panda-small", spec), 2, master_seed=5, out_dir=tmp_path / "again")
    assert [p.read_bytes() for p in again] == [p.read_bytes() for p in paths]
