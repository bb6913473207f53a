"""``simmer check`` on the time-of-flight, IMU and encoder examples: OK, each device called
once, and the summary naming each one's noise settings that are on."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from simmer.cli import app

from helpers import EXAMPLES


@pytest.mark.parametrize(
    ("example", "sensors", "noisy", "quiet"),
    [
        (
            "tof_rover.toml",
            "3 sensors (t0 tof, t1 tof, t2 tof)",
            ["t1 error_constant", "t2 error_constant"],
            ["t0 "],  # its error set to 0, and a VL53L0X has no constant error
        ),
        (
            "motion_rover.toml",
            "3 sensors (i0 imu, e0 encoder, e1 encoder)",
            [
                "i0 gyro_noise_density and gyro_bias and gyro_bias_walk and accel_noise_density "
                "and accel_bias_walk",
                "e0 slip",
                "e1 slip",
            ],
            ["accel_bias and"],
        ),
    ],
)
def test_check_summarises_the_new_kinds_and_their_noise(
    example: str, sensors: str, noisy: list[str], quiet: list[str]
) -> None:
    result = CliRunner().invoke(app, ["check", str(EXAMPLES / example)])
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())  # rich wraps the paragraph
    assert text.startswith("OK")
    assert sensors in text
    for words in noisy:
        assert words in text
    noise = text[text.index("Noise:") :]
    for words in quiet:
        assert words not in noise
