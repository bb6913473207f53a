"""One place decides a run's noise seed (``Settings.run_seed``); the simulation and the start
summary both ask it."""

from __future__ import annotations

from typing import Any

from simmer import SimConfig, Simulation
from simmer.config.loader import describe_noise

from helpers import make_config, noisy_data


def config_with(**settings: Any) -> SimConfig:
    """A configuration with noisy devices and these settings."""
    return make_config({**noisy_data(), **settings})


def test_the_seed_is_given_or_configured_or_the_floor_seed() -> None:
    settings = config_with(rand_error=False, floor_seed=11).settings
    assert settings.run_seed() == 11
    assert settings.run_seed(5) == 5
    assert config_with(rand_error=False, floor_seed=11, seed=3).settings.run_seed() == 3


def test_a_fresh_seed_each_run_when_rand_error_is_set() -> None:
    settings = config_with(rand_error=True, seed=3).settings
    assert settings.run_seed(5) == 5
    assert len({settings.run_seed() for _ in range(3)}) == 3


def test_the_simulation_and_its_summary_use_that_seed() -> None:
    config = config_with(rand_error=False, floor_seed=11, seed=3)
    assert Simulation(config).seed == config.settings.run_seed() == 3
    assert Simulation(config, seed=8).seed == 8
    assert "repeatable, seed 3" in describe_noise(config)
    assert "repeatable, seed 8" in describe_noise(config, seed=8)
