"""The ``[link]`` settings: how the serial link between a program and the robot behaves.

Off by default (the simulator answers at once and never drops a byte). A named preset
(``preset = "hc05-9600"``) gives every value; a key set beside it overrides that one value
(``preset = "hc05-9600"`` with ``loss = 0``: the HC-05's timing without its losses);
``preset = "custom"`` starts from a perfect 9600-baud link. :meth:`LinkSettings.resolved` is
the one place that merges them; the model itself is :mod:`simmer.transport.link`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from pydantic import BaseModel, Field, field_validator, model_validator

from simmer.devices.base import SETTINGS_CONFIG

Preset = Literal["off", "custom", "hc05-9600", "hc05-115200"]

MAX_LINK_SECONDS = 60.0
"""Longest ``latency``, ``jitter`` or ``dropout_seconds``: a link slower than a minute per
message is no link; a longer value would hold every reply past any program's timeout."""
MIN_BAUD = 300.0
"""Slowest ``baud``: the slowest rate a serial port offers (a byte then takes 33 ms)."""
MAX_BAUD = 4_000_000.0
"""Fastest ``baud``: faster than any USB-serial or Bluetooth module a robot carries."""


@dataclass(frozen=True)
class LinkParams:
    """A link's resolved values: a preset merged with the keys set beside it."""

    preset: str
    baud: float
    """Bits per second; a byte is 10 bits on the wire (8N1: a start and a stop bit)."""
    latency: float
    """Seconds each message waits before its first byte moves (the radio's turnaround)."""
    jitter: float
    """Most seconds added to ``latency``, drawn uniformly per message."""
    loss: float
    """Chance that one byte is lost (either way)."""
    corruption: float
    """Chance that one byte arrives with one bit flipped."""
    dropout_every: float
    """Mean simulated seconds between dropouts (drawn exponentially; 0: never)."""
    dropout_seconds: float
    """How long a dropout lasts: every byte sent meanwhile is lost."""

    @property
    def byte_seconds(self) -> float:
        """Seconds one byte takes on the wire (10 bits at ``baud``)."""
        return 10.0 / self.baud


PRESETS: dict[str, LinkParams] = {
    "custom": LinkParams("custom", 9600.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    "hc05-9600": LinkParams("hc05-9600", 9600.0, 0.012, 0.008, 1e-4, 1e-5, 180.0, 1.5),
    "hc05-115200": LinkParams("hc05-115200", 115200.0, 0.012, 0.008, 2e-3, 1e-5, 180.0, 1.5),
}
"""The named links: an HC-05 at its default 9600 baud (SPP turnaround about 12 ms, up to
8 ms more; a byte in 10,000 lost, as an Arduino's SoftwareSerial buffer overflows now and
then; a 1.5 s dropout every three minutes on average, the motors browning the robot out), and
at 115200 baud (ten times the bytes per second, but SoftwareSerial drops far more of them).
Plausible figures, not measurements: fit a team's own with the tap and calibration."""


class LinkSettings(BaseModel):
    """How the link to the robot behaves: bytes take time, are lost, corrupted, drop out."""

    model_config = SETTINGS_CONFIG

    preset: Preset = Field(
        "off",
        description="'off' (the default: replies at once, nothing lost), 'hc05-9600', "
        "'hc05-115200' (an HC-05 Bluetooth module), or 'custom' (a perfect 9600-baud link, "
        "changed by the keys below). A key below overrides the preset's value.",
    )
    baud: float | None = Field(
        None,
        description=f"Bits per second, {MIN_BAUD:g} to {MAX_BAUD:,.0f}; a byte is 10 bits "
        "(9600: 1.04 ms a byte).",
    )
    latency: float | None = Field(
        None,
        description=f"Seconds (at most {MAX_LINK_SECONDS:g}) each message waits before its "
        "first byte moves.",
    )
    jitter: float | None = Field(
        None,
        description=f"Most seconds (at most {MAX_LINK_SECONDS:g}) added to latency, drawn "
        "uniformly per message.",
    )
    loss: float | None = Field(
        None, ge=0, le=1, description="Chance that a byte is lost, either way (0 to 1)."
    )
    corruption: float | None = Field(
        None, ge=0, le=1, description="Chance that a byte arrives with one bit flipped (0 to 1)."
    )
    dropout_every: float | None = Field(
        None,
        ge=0,
        description="Mean simulated seconds between dropouts, drawn exponentially (0: never).",
    )
    dropout_seconds: float | None = Field(
        None,
        description=f"Seconds (at most {MAX_LINK_SECONDS:g}) a dropout lasts; every byte sent "
        "meanwhile is lost.",
    )

    @field_validator("baud")
    @classmethod
    def _baud(cls, value: float | None) -> float | None:
        if value is not None and not MIN_BAUD <= value <= MAX_BAUD:
            raise ValueError(
                f"{value:g} baud is outside {MIN_BAUD:g} to {MAX_BAUD:,.0f} (MIN_BAUD, "
                "MAX_BAUD in simmer/config/link.py); an HC-05 runs at 9600 unless set otherwise"
            )
        return value

    @field_validator("latency", "jitter", "dropout_seconds")
    @classmethod
    def _seconds(cls, value: float | None) -> float | None:
        if value is not None and not 0 <= value <= MAX_LINK_SECONDS:
            raise ValueError(
                f"{value:g} s is outside 0 to {MAX_LINK_SECONDS:g} s (MAX_LINK_SECONDS in "
                "simmer/config/link.py); a Bluetooth link's is tens of milliseconds"
            )
        return value

    @model_validator(mode="after")
    def _keys_need_a_link(self) -> LinkSettings:
        if self.preset == "off":
            given = sorted(k for k in self._given())
            if given:
                raise ValueError(
                    f"link.{given[0]} is set but link.preset is 'off' (the link model is off); "
                    "set preset = 'custom' or a named preset such as 'hc05-9600'"
                )
        return self

    def _given(self) -> dict[str, float]:
        """The keys set beside the preset (a recorded run writes the others as null)."""
        fields = self.model_fields_set - {"preset"}
        return {k: v for k in fields if (v := getattr(self, k)) is not None}

    @property
    def on(self) -> bool:
        """Whether the link model is on."""
        return self.preset != "off"

    def resolved(self) -> LinkParams | None:
        """The link's values: the preset's, with each key set here instead (None: off)."""
        if self.preset == "off":
            return None
        return LinkParams(**{**PRESETS[self.preset].__dict__, **self._given()})
