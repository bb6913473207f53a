"""Test setup: no window ever opens (SDL dummy drivers); the slow tests go first; a test not
marked slow fails if it takes more than two CPU seconds; the same generated examples on every
run; a fixture keeping a CPU busy, and one giving Ctrl-C its usual effect."""

import os
import resource
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import settings

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
# As in a terminal that activated SimMeR's environment (the README's set-up): `python` in a
# `--program` command is the first on PATH, this environment's.
os.environ["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), os.environ["PATH"]])
sys.path.insert(0, str(Path(__file__).parent))

settings.register_profile("repeatable", derandomize=True, database=None)
"""The suite's generated tests (fuzzing, properties) draw the same examples on every run, so
a run passes or fails the same way on any machine; ``--hypothesis-profile explore`` draws new
ones each time, to look for what these miss."""
settings.register_profile("explore", derandomize=False)
settings.load_profile("repeatable")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The ``fresh`` and ``slow`` tests first (in their order; the rest after, in theirs): the
    suite is spread over every CPU (``-n auto``, two tests at a time to each worker as it frees
    up: ``--maxschedchunk 2`` in pyproject.toml), and a test of seconds started last would keep
    one CPU busy after the others are done."""

    def order(item: pytest.Item) -> int:
        if item.get_closest_marker("fresh") is not None:
            return 0
        return 1 if item.get_closest_marker("slow") is not None else 2

    items.sort(key=order)


QUICK_TEST_CPU_SECONDS = 2.0
"""CPU seconds a test not marked ``slow`` (or ``fresh``) may use in the quick loop: plain
``pytest`` leaves the marked ones out and must stay under a minute on two cores."""
WHOLE_SUITE_CPU_SECONDS = 2 * QUICK_TEST_CPU_SECONDS
"""The same bound when every test runs (``-m ""``, the README's and CI's command), where other
work shares the cores: a test's CPU time grows under load too (a sweep-file test that used 1.4
CPU seconds quiet used 2.3 beside other suites), so the whole suite allows twice the quick
loop's bound and still fails a test that belongs among the slow ones."""
_CPU_AT_CALL = pytest.StashKey[float]()


def cpu_seconds() -> float:
    """CPU seconds used so far by this process (every thread) and its waited-for children."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


@pytest.fixture(scope="session", autouse=True)
def compiled_kernels() -> None:
    """Load the Numba kernels from their cache (scripts/setup.py compiled them there once)
    before any test's body, or compile them where no set-up did: about a second of CPU, which
    would otherwise count against whichever quick test first drives or reads a sensor."""
    from simmer.warmup import compile_kernels

    compile_kernels()


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_call(item: pytest.Item) -> None:
    """Note the CPU time as the test's body starts (its fixtures are set up by now)."""
    item.stash[_CPU_AT_CALL] = cpu_seconds()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> pytest.TestReport:
    """Fail a passing test not marked ``slow`` whose body used more than its CPU bound
    (:data:`QUICK_TEST_CPU_SECONDS` in the quick loop, :data:`WHOLE_SUITE_CPU_SECONDS` when
    slow tests run too), so the quick loop stays quick.

    CPU time, not wall time: the suite runs on every core while other work shares them (two
    busy cores in CI), and a test's wall time then grows with the load far more than the CPU
    time of this process (all its threads) and of the children it waited for does. A test
    that only waits (a timeout, a sleep) is not caught here: ``--durations`` shows it.
    """
    report: pytest.TestReport = yield
    quick = item.get_closest_marker("slow") is None and item.get_closest_marker("fresh") is None
    if report.when == "call" and report.passed and quick and _CPU_AT_CALL in item.stash:
        used = cpu_seconds() - item.stash[_CPU_AT_CALL]
        name, bound = cpu_bound(item.config)
        if used > bound:
            report.outcome = "failed"
            report.longrepr = (
                f"this test used {used:.1f} CPU seconds, more than {name} ({bound:g}) in "
                "tests/conftest.py: mark it @pytest.mark.slow, or make it quicker"
            )
    return report


def cpu_bound(config: pytest.Config) -> tuple[str, float]:
    """The CPU bound of an unmarked test in this run, and its name: the quick loop's when the
    run leaves slow tests out (``-m 'not slow ...'``), the whole suite's otherwise."""
    if "not slow" in (config.getoption("markexpr") or ""):
        return "QUICK_TEST_CPU_SECONDS", QUICK_TEST_CPU_SECONDS
    return "WHOLE_SUITE_CPU_SECONDS", WHOLE_SUITE_CPU_SECONDS


@pytest.fixture
def busy_cpu() -> Iterator[None]:
    """Another process keeping a CPU busy while the test runs (runs must not notice)."""
    hog = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    yield
    hog.kill()
    hog.wait()


@pytest.fixture
def ctrl_c() -> Iterator[None]:
    """SIGINT raises KeyboardInterrupt here, and the processes the test starts get SIGINT's
    default, even when pytest was started with SIGINT ignored (``nohup``, ``cmd &`` in a
    script): Python then leaves it ignored, and its children inherit that."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


@pytest.hookimpl(optionalhook=True)  # xdist's hook: a run without xdist does not know it
def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """``-n auto`` runs one worker more than there are CPUs: the slow tests spend much of their
    time waiting (a page's real-time window runs, a robot driving its routine in real time,
    child processes starting), and the spare worker keeps both CPUs busy meanwhile."""
    return (os.cpu_count() or 1) + 1
