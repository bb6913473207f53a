"""simmer.ending.RunEnd: the one vocabulary of how a run ended, spelt as the files that users
read have always spelt it (report.json, report.md, results.csv, summary.md)."""

from __future__ import annotations

import json

from simmer.ending import RunEnd


def test_each_end_is_written_as_it_always_was() -> None:
    assert [str(end) for end in RunEnd] == [
        "quit",
        "seconds",
        "program",
        "timeout",
        "error",
        "closed",
        "ok",
        "invalid",
        "crashed",
        "stopped",
    ]
    assert json.dumps({"ended_by": RunEnd.PROGRAM}) == '{"ended_by": "program"}'
    assert f"{RunEnd.TIMEOUT}" == "timeout"


def test_report_md_says_a_served_run_s_end_in_the_same_words() -> None:
    assert {end.value: end.words for end in RunEnd if end.words != end.value} == {
        "quit": "stopped by hand (Esc, closing the window, Ctrl-C or a signal)",
        "seconds": "the --seconds limit of simulated time was reached",
        "program": "the control program exited",
        "timeout": "the --timeout wall-clock limit was reached; the program was stopped",
        "error": "an error stopped it",
        "closed": "the recording was closed",
    }


def test_an_unknown_ending_in_a_report_is_shown_as_it_is() -> None:
    assert RunEnd.words_for("quit") == RunEnd.QUIT.words
    assert RunEnd.words_for("gone fishing") == "gone fishing"
    assert RunEnd.words_for(3) == 3
    assert RunEnd.words_for(["quit"]) == ["quit"]


def test_summary_md_labels() -> None:
    assert {end.value: end.label for end in RunEnd if end.label != end.value} == {
        "ok": "finished",
        "error": "failed",
        "seconds": "simulated-time limit",
        "timeout": "wall-clock limit",
    }


def test_a_sweep_status_as_a_report_says_it() -> None:
    assert RunEnd.OK.reported is RunEnd.PROGRAM
    for end in (RunEnd.ERROR, RunEnd.SECONDS, RunEnd.TIMEOUT):
        assert end.reported is end


def test_a_served_run_s_end_as_a_sweep_s_results_say_it() -> None:
    assert RunEnd.PROGRAM.as_result(0) is RunEnd.OK
    assert RunEnd.PROGRAM.as_result(3) is RunEnd.ERROR
    assert RunEnd.SECONDS.as_result(None) is RunEnd.SECONDS
    assert RunEnd.TIMEOUT.as_result(None) is RunEnd.TIMEOUT
    assert RunEnd.ERROR.as_result(None) is RunEnd.ERROR
    assert RunEnd.CLOSED.as_result(None) is RunEnd.ERROR
