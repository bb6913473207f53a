"""The link model (simmer.transport.link): timing at a baud rate, loss and corruption rates,
dropouts, one seeded stream per source; and its [link] settings."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from tests.helpers import default_data, make_config

from simmer.config.link import PRESETS, LinkParams, LinkSettings
from simmer.transport.link import TO_PROGRAM, TO_ROBOT, LinkModel

BYTE_9600 = 10 / 9600


def streams(seed: int) -> object:
    """A stream factory like Simulation.stream: one generator per source name."""

    def stream(name: str) -> np.random.Generator:
        key = sum(name.encode())
        return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(key,)))

    return stream


def model(seed: int = 1, **changes: float) -> LinkModel:
    params = dataclasses.replace(PRESETS["custom"], **changes)
    return LinkModel(params, streams(seed))  # type: ignore[arg-type]


def test_a_reply_at_9600_baud_takes_its_bytes_time_and_the_latency() -> None:
    link = model(latency=0.012)
    command = link.carry(b"u0\n", 1.0, TO_ROBOT)
    assert command.arrives == pytest.approx(1.0 + 0.012 + 3 * BYTE_9600)
    reply = link.carry(b"\x04\x01\x00" + b"\x00" * 4, command.arrives, TO_PROGRAM)
    # a packed 7-byte frame: 3 + 7 bytes at 1.0417 ms, two latencies
    assert reply.arrives - 1.0 == pytest.approx(2 * 0.012 + 10 * BYTE_9600)
    assert reply.data == b"\x04\x01\x00" + b"\x00" * 4
    assert link.counts.bytes == 10
    assert link.counts.messages == 2


def test_a_reply_never_leaves_before_its_command_arrives_nor_overtakes() -> None:
    link = model()
    command = link.carry(b"x" * 96, 0.0, TO_ROBOT)  # 0.1 s on the wire
    reply = link.carry(b"y", 0.0, TO_PROGRAM)
    assert reply.arrives == pytest.approx(command.arrives + BYTE_9600)
    second = link.carry(b"z", 0.0, TO_PROGRAM)  # the wire is busy until the first is through
    assert second.arrives == pytest.approx(reply.arrives + BYTE_9600)


def test_jitter_stays_within_its_bound_and_spreads() -> None:
    link = model(latency=0.01, jitter=0.008, baud=4_000_000)
    waits = [link.carry(b"", 100.0 * i, TO_ROBOT).arrives - 100.0 * i for i in range(2000)]
    assert min(waits) >= 0.01
    assert max(waits) <= 0.018 + 1e-12
    assert np.mean(waits) == pytest.approx(0.014, abs=0.0005)  # uniform: the bound's middle


@pytest.mark.parametrize(("loss", "corruption"), [(0.01, 0.0), (0.0, 0.003), (0.002, 0.02)])
def test_loss_and_corruption_rates_over_100000_bytes(loss: float, corruption: float) -> None:
    link = model(loss=loss, corruption=corruption)
    rng = np.random.default_rng(7)
    sent = received = flipped = 0
    while sent < 100_000:  # messages of 1 to 199 bytes, as a program sends them
        data = rng.integers(0, 256, rng.integers(1, 200), dtype=np.uint8).tobytes()
        got = link.carry(data, 0.0, TO_ROBOT).data
        sent += len(data)
        received += len(got)
        if not loss:
            flipped += sum(a != b for a, b in zip(data, got, strict=True))
    lost = sent - received
    for rate, count in ((loss, lost), (corruption, link.counts.corrupted)):
        expected = rate * sent
        # within 4 standard deviations of a binomial count (a test that fails 1 in 15,000)
        assert abs(count - expected) <= 4 * math.sqrt(expected * (1 - rate)) + 1
    assert link.counts.lost == lost
    if not loss:
        assert flipped == link.counts.corrupted  # one bit flipped: the byte differs


def test_a_bytes_fate_depends_on_its_place_not_on_how_messages_split_it() -> None:
    data = bytes(range(256)) * 40
    whole = model(seed=3, loss=0.01, corruption=0.01).carry(data, 0.0, TO_ROBOT).data
    split = model(seed=3, loss=0.01, corruption=0.01)
    pieces = (data[i : i + 37] for i in range(0, len(data), 37))
    parts = b"".join(split.carry(piece, 0.0, TO_ROBOT).data for piece in pieces)
    assert parts == whole != data


def test_dropouts_start_at_exponential_intervals_and_last_their_length() -> None:
    link = model(dropout_every=10.0, dropout_seconds=1.5, baud=4_000_000)
    starts: list[float] = []
    t = 0.0
    down_before = False
    while t < 5000.0:  # a byte every 20 ms for 5,000 simulated seconds
        down = link.carry(b"?", t, TO_ROBOT).dropout
        if down and not down_before:
            starts.append(t)
        down_before = down
        t += 0.02
    gaps = np.diff(starts)
    assert link.counts.dropouts == len(starts)
    # 5000 s / (10 s between + 1.5 s down) ~ 435 dropouts; mean gap between starts 11.5 s
    assert 380 <= len(starts) <= 490
    assert np.mean(gaps) == pytest.approx(11.5, rel=0.1)
    assert gaps.min() >= 1.5 - 0.021  # the link is down for its whole length before the next
    assert link.counts.in_dropout == pytest.approx(len(starts) * 75, rel=0.02)


def test_the_link_comes_back_after_the_dropout() -> None:
    link = model(dropout_every=5.0, dropout_seconds=2.0)
    start, end = link.window
    assert not link.carry(b"a", start - 0.001, TO_ROBOT).dropout
    assert link.carry(b"b", start, TO_ROBOT).data == b""
    assert link.carry(b"c", start + 1.999, TO_ROBOT).dropout
    assert link.carry(b"d", end + 0.01, TO_ROBOT).data == b"d"
    assert end - start == 2.0
    assert link.counts.dropouts == 1


def test_the_same_seed_gives_the_same_link_and_each_source_its_own_stream() -> None:
    def run(seed: int, jitter: float = 0.01) -> list[tuple[bytes, float]]:
        link = model(seed, loss=0.05, corruption=0.05, jitter=jitter, dropout_every=1.0,
                     dropout_seconds=0.2)  # fmt: skip
        carried = (link.carry(b"w0-6\n", i * 0.1, TO_ROBOT) for i in range(300))
        return [(c.data, c.arrives) for c in carried]

    assert run(5) == run(5)
    assert run(5) != run(6)
    # no jitter: the losses are the same bytes (each source draws from its own stream)
    same_losses = [d for d, _ in run(5, jitter=0.0)]
    assert same_losses == [d for d, _ in run(5)]


def test_presets_and_keys_beside_them() -> None:
    assert LinkSettings().resolved() is None
    hc05 = LinkSettings(preset="hc05-9600", loss=0.0).resolved()
    assert isinstance(hc05, LinkParams)
    assert (hc05.baud, hc05.loss, hc05.latency) == (9600.0, 0.0, PRESETS["hc05-9600"].latency)
    assert hc05.byte_seconds == pytest.approx(BYTE_9600)


def test_a_key_with_the_link_off_is_one_plain_line_naming_it() -> None:
    data = default_data()
    data["link"] = {"baud": 9600}
    with pytest.raises(Exception, match=r"link\.baud is set but link\.preset is 'off'.*custom"):
        make_config(data)
    data["link"] = {"preset": "hc05-9600", "baud": 1}
    with pytest.raises(Exception, match=r"link\.baud.*1 baud is outside 300 to .*MIN_BAUD"):
        make_config(data)
    data["link"] = {"preset": "hc05-9600", "latency": 3600}
    with pytest.raises(Exception, match=r"link\.latency.*outside 0 to 60 s \(MAX_LINK_SECONDS"):
        make_config(data)


def test_simmer_check_says_the_link_model_is_on(tmp_path: Path) -> None:
    from typer.testing import CliRunner

    from simmer.cli import app

    path = tmp_path / "robot.toml"
    path.write_text('[link]\npreset = "hc05-9600"\nloss = 0.001\n', encoding="utf-8")
    said = CliRunner().invoke(app, ["check", str(path)]).output
    assert "Link model hc05-9600: 9600 baud, 12 ms latency, 0.001 of bytes lost" in said
    path.write_text("", encoding="utf-8")
    assert "Link model" not in CliRunner().invoke(app, ["check", str(path)]).output
