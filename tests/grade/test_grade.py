"""simmer grade end to end: four teams written as students write (plain two-port sockets, an
input() prompt for the target): one good, one slow, one that crashes half-way, one that hangs
without reading its prompt; every number of the leaderboard checked, and the same tables on 1
and 2 workers, resumed, and for one team alone (a student's --only)."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import pytest

from grade_support import GOOD, grading_folder
from simmer.grade import load_grading, run_grading
from simmer.sweep import local_pool


def _csv(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as file:
        return list(csv.DictReader(file))


def _without_wall_time(path: Path) -> list[dict[str, str]]:
    return [{k: v for k, v in r.items() if k != "wall_time"} for r in _csv(path)]


@pytest.mark.slow
@pytest.mark.timeout(900)  # 20 program runs: ~95 s alone here, several times that on 2 busy cores
def test_four_teams_ranked_with_every_number_and_the_same_on_1_and_2_workers(
    tmp_path: Path,
) -> None:
    spec = load_grading(grading_folder(tmp_path / "course"))
    one = run_grading(spec, tmp_path / "one", engine=local_pool(1), workers=1, source="G")
    two = run_grading(spec, tmp_path / "two", engine=local_pool(2), workers=2, source="G")

    board = _csv(tmp_path / "one" / "leaderboard.csv")
    assert [r["team"] for r in board] == ["Good", "Slow", "Crash", "Hang"]
    runs = _csv(tmp_path / "one" / "results.csv")
    by = {(r["team"], r["scenario.target"]): r for r in runs}
    assert len(runs) == 8
    # Good and Slow deliver everywhere (10 + 20 + 10 + 60 points); Slow's waits make it later
    for team in ("Good", "Slow"):
        for target in ("B1", "B3"):
            r = by[team, target]
            assert (r["delivered"], r["score"], r["collisions"]) == ("True", "100.0", "0")
    good, slow, crash, hang = board
    for line in (good, slow):
        assert (line["score"], line["successes"], line["runs"]) == ("100.00", "2", "2")
        assert (line["violations"], line["crashes"], line["collisions"]) == ("0", "0", "0")
    mean = {
        team: (float(by[team, "B1"]["delivered_at"]) + float(by[team, "B3"]["delivered_at"])) / 2
        for team in ("Good", "Slow")
    }
    assert good["time"] == f"{mean['Good']:.2f}"
    assert slow["time"] == f"{mean['Slow']:.2f}"
    assert mean["Slow"] > mean["Good"] + 60  # half a second before each of its commands
    # Crash picks the block up, then raises: 10 + 20 points, its traceback's last line kept
    for target in ("B1", "B3"):
        r = by["Crash", target]
        assert (r["status"], r["exit_status"], r["score"]) == ("error", "1", "30.0")
        assert (r["picked_up"], r["left_loading"]) == ("True", "False")
        assert r["detail"].endswith("RuntimeError: team Crash: forgot to write the rest")
        assert 'File "robot.py"' in r["detail"]  # not the box's scratch folder
    assert (crash["score"], crash["successes"], crash["violations"], crash["crashes"]) == (
        "30.00",
        "0",
        "2",
        "2",
    )
    # Hang never reads its prompt or sends anything: stopped at the simulated-time limit
    for target in ("B1", "B3"):
        r = by["Hang", target]
        assert (r["status"], r["messages"], r["score"], r["time"]) == (
            "seconds",
            "0",
            "0.0",
            "300.0",
        )
    assert (hang["score"], hang["successes"], hang["violations"]) == ("0.00", "0", "4")
    log = _csv(tmp_path / "one" / "violations.csv")
    assert sorted((r["team"], r["violation"]) for r in log) == sorted(
        [("Crash", "crash")] * 2 + [("Hang", "never-connected")] * 2 + [("Hang", "time-limit")] * 2
    )
    # the reports and the page
    report = (tmp_path / "one" / "teams" / "Crash.md").read_text(encoding="utf-8")
    assert "RuntimeError: team Crash: forgot to write the rest" in report
    page = (tmp_path / "one" / "index.html").read_text(encoding="utf-8")
    assert (
        page.index(">Good<") < page.index(">Slow<") < page.index(">Crash<") < page.index(">Hang<")
    )
    assert "simmer replay runs/Good_target=B1_seed1 runs/Good_target=B3_seed1" in page
    side = [f"runs/{team}_target=B3_seed1" for team in ("Good", "Slow", "Crash", "Hang")]
    assert f"simmer replay {' '.join(side)}</code>" in page  # side by side, best first
    assert f"simmer render {' '.join(side)} -o compare-target=B3_seed1.mp4" in page
    assert (tmp_path / "one" / "teams" / "Good.png").read_bytes()[:4] == b"\x89PNG"
    # 1 and 2 workers: the same tables
    for name in ("leaderboard.csv", "leaderboard.md", "violations.csv"):
        assert (tmp_path / "one" / name).read_bytes() == (tmp_path / "two" / name).read_bytes()
    assert _without_wall_time(tmp_path / "one" / "results.csv") == _without_wall_time(
        tmp_path / "two" / "results.csv"
    )
    assert [s.team.name for s in one.standings] == [s.team.name for s in two.standings]

    # an interrupted grading resumes: drop two rows, run again, only they run
    resumed = tmp_path / "resumed"
    shutil.copytree(tmp_path / "one", resumed)
    lines = (resumed / "results.csv").read_text(encoding="utf-8").splitlines(keepends=True)
    (resumed / "results.csv").write_text("".join(lines[:-2]), encoding="utf-8")
    again = run_grading(spec, resumed, engine=local_pool(1), workers=1, resume=True, source="G")
    assert again.ran == 2
    assert (resumed / "leaderboard.csv").read_bytes() == (
        tmp_path / "one" / "leaderboard.csv"
    ).read_bytes()

    # a student's side: --only their folder gives their line, the same as in the TA's table
    mine = spec.only(tmp_path / "course" / "teams" / "slow")
    alone = run_grading(mine, tmp_path / "mine", engine=local_pool(1), workers=1, source="G")
    assert [s.team.name for s in alone.standings] == ["Slow"]
    line = _csv(tmp_path / "mine" / "leaderboard.csv")[0]
    assert {k: v for k, v in line.items() if k != "rank"} == {
        k: v for k, v in slow.items() if k != "rank"
    }


GIVES_UP = '\nforward(3)  # three inches, then it gives up\nraise SystemExit("gave up")\n'


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_each_team_s_first_failures_are_filmed_and_linked_once(tmp_path: Path) -> None:
    """videos = 1: a team that drives three inches and gives up gets one video, of its first
    failing scenario, that plays the run; the good team none; --resume films nothing again."""
    import av

    main_call = 'if __name__ == "__main__":\n    main()\n'
    assert main_call in GOOD
    teams = {"Good": GOOD, "Quits": GOOD.replace(main_call, GIVES_UP)}
    spec = load_grading(grading_folder(tmp_path / "course", "videos = 1", teams))
    done = run_grading(spec, tmp_path / "out", engine=local_pool(1), workers=1)
    assert done.filmed == 1
    rows = _csv(tmp_path / "out" / "results.csv")
    quits = [r for r in rows if r["team"] == "Quits"]
    assert [r["status"] for r in quits] == ["error", "error"]
    videos = sorted(p.relative_to(tmp_path / "out") for p in (tmp_path / "out").rglob("*.mp4"))
    assert [str(v) for v in videos] == ["runs/Quits_target=B1_seed1/video.mp4"]
    with av.open(str(tmp_path / "out" / videos[0])) as container:
        stream = container.streams.video[0]
        frames = sum(1 for _ in container.decode(stream))
        assert stream.duration is not None
        assert stream.time_base is not None
        seconds = float(stream.duration * stream.time_base)
    assert frames > 0
    assert seconds == pytest.approx(float(quits[0]["time"]), abs=0.5)  # the run, played
    page = (tmp_path / "out" / "index.html").read_text(encoding="utf-8")
    assert '<a href="runs/Quits_target=B1_seed1/video.mp4">video</a>' in page
    again = run_grading(spec, tmp_path / "out", engine=local_pool(1), workers=1, resume=True)
    assert (again.ran, again.filmed) == (0, 0)
