"""Grading: several teams' programs over the same scenarios, each in a box, ranked on a
leaderboard (``simmer grade GRADING.toml``; a student's ``--only .``).

:func:`load_grading` reads the grading file (:mod:`simmer.grade.spec`), :func:`run_grading`
runs every team's program in every scenario on the sweep's engine
(:mod:`simmer.grade.engine`), each run boxed (:mod:`simmer.lockstep.box`), and writes
results.csv, the leaderboard, the teams' reports and the violation log
(:mod:`simmer.grade.board`).
"""

from simmer.grade.board import VIOLATIONS, Standing, standings, violations
from simmer.grade.engine import GradeResult, run_grading
from simmer.grade.spec import GradeSpec, Scenario, Team, load_grading

__all__ = [
    "VIOLATIONS",
    "GradeResult",
    "GradeSpec",
    "Scenario",
    "Standing",
    "Team",
    "load_grading",
    "run_grading",
    "standings",
    "violations",
]
