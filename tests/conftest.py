import os
import sys
import time

# One BLAS thread per process, set before numpy loads its BLAS (the test processes, the pytest beside the suite and
# the subprocesses they start inherit it): the suite runs two pytests side by side on CI's two cores, and a BLAS of two
# threads in each then waits for a busy core on every small call (a 6 x 6 triangular solve took 24-51 ms under that
# load, 0.1 ms on one thread; test_uncertainty and test_convex used 22 s of CPU against 15 s). Tests that need more
# threads ask for them (threadpool_limits); a value set by hand is kept.
for _blas in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_blas, "1")

# Bytecode is written while the suite runs, PYTHONDONTWRITEBYTECODE or not: with it set (as on this project's machines),
# every process the suite starts (worker processes, Dask workers, notebook kernels, the pytest beside it, the commands
# it runs) compiled graybox's 43,000 lines again, and pytest rewrote the tests' asserts again in each pytest (17 s of
# the suite's collection). Measured on 2 cores: 435 s with it set, 420 s without, from a fresh checkout (BENCHMARKS.md).
# The caches land in the ``__pycache__`` folders the numba kernels' caches already use (git ignores them).
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

import numpy as np
import pytest
from hypothesis import settings

# Property tests draw the same examples on every run: CI must not pass or fail by luck. Run with
# HYPOTHESIS_PROFILE=explore to search new examples.
settings.register_profile("deterministic", derandomize=True, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))

from graybox import Record


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def steps_input(n: int, rng, lo: float = 750.0, hi: float = 1650.0, hold: int = 60) -> np.ndarray:
    """A piecewise-constant input in rpm, changing every ``hold`` samples."""
    levels = rng.uniform(lo, hi, size=n // hold + 1)
    return np.repeat(levels, hold)[:n]


@pytest.fixture
def paper_record(rng):
    """A record simulated from the paper's ELS model (15) under step inputs."""
    from graybox import reference

    m = reference.paper_model(15)
    u = steps_input(1200, rng)
    y0 = np.full(m.max_lag, float(m.static_curve([u[0]])[0]))
    y = m.simulate(u, y0)
    return Record(u, y, Ts=0.05, name="sim15")


def traced_peak(call) -> int:
    """The peak of memory traced while ``call()`` runs (bytes; numpy's arrays are traced), after a collection."""
    import gc
    import tracemalloc

    gc.collect()
    tracemalloc.start()
    try:
        call()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def two_level_records(names: tuple[str, str] = ("ident", "valid")):
    """Two records of y(k) = 0.5 y(k-1) + 0.4 u(k-1) + 0.1 u(k-1)² + 0.2 (+ noise 0.01), the first's input at two
    levels only (u² a combination of u and 1 there: λ1 = 1, no weight on the static points, cannot identify a
    structure holding both), the second's over [0, 3]; and static points from the true curve at seven levels."""
    from graybox import StaticPoints

    rng = np.random.default_rng(0)

    def plant(u):
        y = np.zeros_like(u)
        for k in range(1, len(u)):
            y[k] = 0.5 * y[k - 1] + 0.4 * u[k - 1] + 0.1 * u[k - 1] ** 2 + 0.2
        return y + 0.01 * rng.standard_normal(len(u))

    u1, u2 = np.repeat(rng.choice([1.0, 2.0], 40), 10), np.repeat(rng.uniform(0.0, 3.0, 40), 10)
    ub = np.linspace(0.0, 3.0, 7)
    return (Record(u1, plant(u1), name=names[0]), Record(u2, plant(u2), name=names[1]),
            StaticPoints(ub, (0.2 + 0.4 * ub + 0.1 * ub**2) / 0.5))


def staircase_plant(seed: int, n: int = 400, noise: float = 0.02):
    """A record of y(k) = 0.6 y(k-1) + 0.2 y(k-2) + 0.3 u(k-1) + 0.05 u(k-2)² + 0.4 (+ white noise of std
    ``noise``), u held 25 samples at levels drawn from [0, 3]: the selection tests' small plant (STAIRCASE_TRUE)."""
    from graybox import Model

    rng = np.random.default_rng(seed)
    u = np.repeat(rng.uniform(0.0, 3.0, n // 25 + 1), 25)[:n]
    y = Model(STAIRCASE_TRUE, STAIRCASE_THETA).simulate(u, np.zeros(2)) + noise * rng.standard_normal(n)
    return Record(u, y, name=f"r{seed}")


STAIRCASE_TRUE = ["y(k-1)", "y(k-2)", "u(k-1)", "u(k-2)^2", "1"]
STAIRCASE_THETA = np.array([0.6, 0.2, 0.3, 0.05, 0.4])


#: The quadratic first-order plant of the choosing tests: y(k) = 0.2 + 0.6 y(k-1) + 0.3 u(k-1) + 0.05 u(k-1)².
QUADRATIC_FIRST_ORDER = ["1", "y(k-1)", "u(k-1)", "u(k-1)^2"]


def quadratic_first_order_data(seed: int):
    """A Dataset of QUADRATIC_FIRST_ORDER (θ = 0.2, 0.6, 0.3, 0.05): ident and valid of 300 samples each, u held 5
    samples at levels drawn from [0.5, 2], output noise of std 0.02, five exact static points on [0.5, 2]."""
    import graybox as gb

    rng = np.random.default_rng(seed)
    model = gb.Model(QUADRATIC_FIRST_ORDER, [0.2, 0.6, 0.3, 0.05])

    def rec(n, name):
        u = np.repeat(rng.uniform(0.5, 2.0, n // 5), 5)
        return gb.Record(u, model.simulate(u, np.zeros(1)) + 0.02 * rng.standard_normal(u.size), name=name)

    ub = np.linspace(0.5, 2.0, 5)
    return gb.Dataset(rec(300, "ident"), rec(300, "valid"), gb.StaticPoints(ub, (0.2 + 0.3 * ub + 0.05 * ub**2) / 0.4))


def first_order_signals(n: int = 300, seed: int = 0, noise: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """u uniform on [-1, 1] and y(k) = 0.5 y(k-1) + u(k-1) + ``noise`` e(k) (e standard normal): the model
    y(k-1), u(k-1) with θ = (0.5, 1) leaves white residuals (none at ``noise=0``)."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1, 1, n)
    y = np.zeros(n)
    for k in range(1, n):
        y[k] = 0.5 * y[k - 1] + u[k - 1] + noise * rng.standard_normal()
    return u, y


def assert_csv_pair_matches(dyn, sta, committed, ncols: tuple[int, int]) -> None:
    """Regenerated bundled CSVs equal the committed ones: same header and rows, every column but the
    last (pressure) exactly, the pressure to one unit of its 4th decimal (a last-ulp difference on
    another platform can flip the printed rounding by that unit, never more)."""
    for new, old, n in ((dyn, committed / "dynamic.csv", ncols[0]), (sta, committed / "static.csv", ncols[1])):
        new_lines = new.read_text().splitlines()
        old_lines = old.read_text().splitlines()
        assert new_lines[0] == old_lines[0]
        assert len(new_lines) == len(old_lines)
        a = np.loadtxt(new_lines[1:], delimiter=",")
        b = np.loadtxt(old_lines[1:], delimiter=",")
        assert a.shape == b.shape and a.shape[1] == n
        np.testing.assert_array_equal(a[:, :-1], b[:, :-1])
        np.testing.assert_allclose(a[:, -1], b[:, -1], rtol=0, atol=1.01e-4)


def edited_file(value, path, edit):
    """``value`` saved at ``path``, then its JSON object changed by ``edit`` (a hand edit); the path."""
    import json

    from graybox import save

    save(value, path)
    j = json.loads(path.read_text())
    edit(j["object"])
    path.write_text(json.dumps(j))
    return path


def edited_json(value, **fields) -> str:
    """``value`` saved as JSON with the given fields of its object replaced: a hand-edited file."""
    import json

    from graybox import to_json

    doc = json.loads(to_json(value))
    doc["object"].update(fields)
    return json.dumps(doc)


# --- the documentation site, built beside the rest of the suite -----------------------------------
# The Sphinx build (tests/test_docs.py) runs every notebook in its own kernel: about a minute of one core, while
# the suite leaves the second core mostly idle. It is started in its own process as the suite begins, and the
# docs tests run last and wait for it. It is the suite's one execution of the notebooks: their checks run in its
# kernels (tests/_notebook_checks.py) and tests/test_notebooks.py reads their verdicts.
DOCS_TESTS = ("test_docs.py", "test_notebooks.py")
_SITE_BUILD = pytest.StashKey[dict]()


def start_site_build() -> dict:
    """Start ``python -m sphinx -W --keep-going -q -b html docs <tmp>/html`` in its own session (its notebook
    kernels are its children); its output goes to files, so a full pipe never stalls it."""
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    tmp = Path(tempfile.mkdtemp(prefix="graybox-docs-"))
    (tmp / "notebook-checks").mkdir()  # the verdicts of the notebooks' checks (tests/_notebook_checks.py)
    with open(tmp / "stdout", "w") as out, open(tmp / "stderr", "w") as err:
        proc = subprocess.Popen([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                                 str(root / "docs"), str(tmp / "html")], stdout=out, stderr=err, cwd=root,
                                stdin=subprocess.DEVNULL, start_new_session=True,
                                env=dict(os.environ, GRAYBOX_NOTEBOOK_CHECKS=str(tmp / "notebook-checks")))
    return {"proc": proc, "tmp": tmp}


def finish_site_build(build: dict) -> tuple[int, str, "object"]:
    """Wait for a build :func:`start_site_build` started: (return code, its stderr, the html folder)."""
    rc = build["proc"].wait()
    return rc, (build["tmp"] / "stderr").read_text(encoding="utf-8", errors="replace"), build["tmp"] / "html"


# --- tests run beside the rest of the suite ---------------------------------------------------------------------
# The suite's tests run one after another in one process; these run in pytests of their own (lanes), started as the
# suite begins, and the suite's items of them run last and take their verdicts. An entry is a file, or a file's test.
# BESIDE: work that keeps a core busy (the README's and the selection guide's select_graybox calls on the bundled
# plant, the files of one process each), so that the suite and it end together. WAITING: tests that mostly
# wait (Dask clusters starting, cell time limits running out, processes killed and replaced): their waits overlap the
# other lanes' work instead of lengthening one of them. `pytest` says each lane's time at the end (2026-11-29, 2 cores,
# a fresh clone: the suite's own tests 363 s, beside 325 s, waiting 354 s, before test_grid_margin and test_hunt44b
# (21 s) moved beside; BENCHMARKS.md): move files between them to keep them even.
BESIDE = ("test_guide_code.py::test_every_python_block_of_a_page_runs[selection.md]",
          "test_readme_api.py::test_selection_example_runs",
          "test_select_checkpoint.py", "test_bootstrap.py", "test_gram.py", "test_hunt36a.py",
          "test_divergence_bound.py", "test_slow_modes.py", "test_hunt30c.py", "test_constant_output.py",
          "test_uncertainty.py", "test_siso_pins.py", "test_control.py",
          "test_select_graybox.py", "test_hunt28.py", "test_grid_growth.py", "test_grid_margin.py", "test_hunt44b.py",
          "test_hunt51a.py")
WAITING = ("test_grid_executors.py", "test_review44d.py", "test_review40d.py", "test_review47e.py", "test_grid42a.py",
           "test_parallel_map_errors.py", "test_grid_claims.py", "test_share41a.py", "test_review42f.py",
           "test_review43d.py", "test_review48i.py", "test_dask_scratch.py", "test_review41e.py",
           "test_mend49d.py::test_a_cell_stopped_past_the_time_limit_on_dask_says_its_child_process_was_stopped_not_its_worker",
           "test_mend49d.py::test_a_cell_stopped_past_the_time_limit_in_a_process_pool_names_its_worker_process")
LANES = {"beside": BESIDE, "waiting": WAITING}
_BESIDE_ENV = "GRAYBOX_TESTS_BESIDE"  # set in that pytest (to the suite's process id): it runs them itself
_BESIDE_RUN = pytest.StashKey[dict]()  # lane name -> its run (start_beside)
_SUITE_START = pytest.StashKey[float]()
_SUITE_END = pytest.StashKey[float]()
#: Seconds the suite waits for a pytest beside it from its start (CI allows 600 for the whole suite), or 1.3 times
#: the suite's own time to its first item of them if that is longer (a loaded machine slows both alike): past them it is
#: killed and its tests fail with its output, rather than the suite waiting on a hung test for ever.
BESIDE_LIMIT = 540


def lane_of(item) -> str | None:
    """The name of the lane (:data:`LANES`) that runs ``item`` beside the suite, or None (the suite runs it)."""
    for name, entries in LANES.items():
        if item.path.name in entries or f"{item.path.name}::{item.name}" in entries:
            return name
    return None


def runs_beside(item) -> bool:
    """Whether ``item`` runs in a pytest beside the suite (one of :data:`LANES`)."""
    return lane_of(item) is not None


def start_beside(items) -> dict:
    """Start ``python -m pytest`` of ``items`` in its own session, its verdicts in a JUnit XML file."""
    import os
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    tmp = Path(tempfile.mkdtemp(prefix="graybox-beside-"))
    # its own base folder for tmp_path: two sessions cleaning the same pytest-of-<user> folder collide
    with open(tmp / "output", "w") as out:
        # a test running past faulthandler_timeout dumps every thread's stack into the output, which the suite shows
        # when this pytest is killed past BESIDE_LIMIT: a hang then says where it waits (a fresh clone's waiting lane
        # hung twice, 2026-11-29, with nothing but its dots to show)
        proc = subprocess.Popen([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                                 "-o", f"faulthandler_timeout={BESIDE_LIMIT // 3}",
                                 f"--basetemp={tmp / 'basetemp'}", f"--junitxml={tmp / 'verdicts.xml'}",
                                 *(item.nodeid for item in items)],
                                stdout=out, stderr=subprocess.STDOUT, cwd=items[0].config.rootpath,
                                stdin=subprocess.DEVNULL, start_new_session=True,
                                env=dict(os.environ, **{_BESIDE_ENV: str(os.getpid())}))
    return {"proc": proc, "tmp": tmp, "start": time.monotonic()}


def _kill_group(proc) -> None:
    """SIGKILL ``proc``'s process group (it runs in a session of its own: its workers and kernels go too)."""
    import os
    import signal

    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


def _end_with_the_suite(suite: int) -> None:
    """In the pytest beside the suite: kill its own process group once the suite's process ``suite`` is gone
    (killed, say), so that no orphaned test keeps the machine busy."""
    import os
    import signal
    import threading

    def watch() -> None:
        while os.getppid() == suite:
            time.sleep(2)
        os.killpg(os.getpgid(0), signal.SIGKILL)

    threading.Thread(target=watch, name="end with the suite", daemon=True).start()


def pytest_configure(config):
    import os

    suite = os.environ.get(_BESIDE_ENV, "")
    # only as start_beside starts it: a child of that suite, leading a process group of its own (the variable set by
    # hand, or inherited, would have it kill a group that is its caller's too)
    if suite.isdigit() and os.getppid() == int(suite) and os.getpgid(0) == os.getpid():
        _end_with_the_suite(int(suite))


def _case_of(item, run: dict, required: bool = True):
    """Wait for the pytest beside the suite; ``item``'s JUnit test case there (failing the item when it has none and
    it is ``required``, else None)."""
    import xml.etree.ElementTree as ET

    import subprocess

    if "rc" not in run:
        try:
            waited = time.monotonic() - run["start"]
            run["rc"] = run["proc"].wait(timeout=max(BESIDE_LIMIT, 1.3 * waited) - waited)
        except subprocess.TimeoutExpired:
            _kill_group(run["proc"])
            run["rc"] = (f"killed: it ran past conftest.BESIDE_LIMIT, {BESIDE_LIMIT} s, and 1.3 times the suite's "
                         f"{waited:.0f} s")
    rc = run["rc"]
    if "cases" not in run:  # (parsed once for all its items)
        try:
            run["cases"] = list(ET.parse(run["tmp"] / "verdicts.xml").getroot().iter("testcase"))
        except (OSError, ET.ParseError):
            run["cases"] = []
    for case in run["cases"]:
        if case.get("name") == item.name and item.path.stem in (case.get("classname") or "").split("."):
            return case
    if not required:
        return None
    output = (run["tmp"] / "output").read_text(encoding="utf-8", errors="replace")
    pytest.fail(f"the pytest beside the suite (rc {rc}) did not run {item.nodeid}:\n{output[-4000:]}", pytrace=False)


def _verdict_of(item, run: dict, when: str) -> None:
    """The suite's item of a test run beside it, at phase ``when``: wait for that pytest, and end as the test did
    there. Its setup sets up no fixture (that pytest did: a module fixture's work is not done twice) and takes the
    skips, xfails and setup errors; its call the failures, its teardown the teardown errors. The item keeps its
    marks, so a strict XPASS there (a failure) is left to them here: they fail it again, where failing it by hand
    under an xfail mark would be taken for an xfail."""
    case = _case_of(item, run, required=when != "teardown")  # (a missing case is said once, by the setup)
    for child in case if case is not None else ():
        said = f"{item.nodeid} failed in the pytest beside the suite:\n{child.text}"
        message = child.get("message") or ""
        if when == "setup" and child.tag == "error" and message.startswith("failed on setup"):
            pytest.fail(said, pytrace=False)
        if when == "setup" and child.tag == "skipped":
            if child.get("type") == "pytest.xfail":
                pytest.xfail(message)
            pytest.skip(message or "skipped beside the suite")
        if when == "call" and child.tag == "failure" and not message.startswith("[XPASS(strict)]"):
            pytest.fail(said, pytrace=False)
        if when == "teardown" and child.tag == "error" and message.startswith("failed on teardown"):
            pytest.fail(said, pytrace=False)


@pytest.hookimpl(trylast=True)  # after -k and -m have deselected
def pytest_collection_modifyitems(session, config, items):
    import os

    if config.option.collectonly:
        return
    beside = [] if os.environ.get(_BESIDE_ENV) else [item for item in items if runs_beside(item)]
    docs = [item for item in items if item.path.name in DOCS_TESTS]
    if beside or docs:
        warm_up(config)  # before the processes that would each compile the kernels start
    if beside:
        runs = config.stash[_BESIDE_RUN] = {}
        for lane in LANES:
            mine = [item for item in beside if lane_of(item) == lane]
            if mine:
                runs[lane] = start_beside(mine)
        for item in beside:
            run = runs[lane_of(item)]
            for when, method in (("setup", "setup"), ("call", "runtest"), ("teardown", "teardown")):
                setattr(item, method, (lambda it, r, w: lambda: _verdict_of(it, r, w))(item, run, when))
        config.stash[_SUITE_START] = time.monotonic()
    last = beside + docs
    if not last:
        return
    items[:] = [item for item in items if item not in last] + last
    if docs:
        config.stash[_SITE_BUILD] = start_site_build()


# --- numba's cache, filled before the processes that read it start ----------------------------------------------------
_WARM_UP = pytest.StashKey[dict]()
#: tests/_warm_kernels.py's parts, run side by side.
WARM_PARTS = ("simulation", "statics")
#: Seconds the suite waits for a part (each takes 20–25 s from a cold cache on 2 cores).
WARM_LIMIT = 240


def warm_kernels() -> dict:
    """Run tests/_warm_kernels.py's parts side by side and wait for them: part -> (return code, its stderr).

    On a fresh checkout (CI's) the suite's pytests, the Sphinx build's notebook kernels and the worker processes all
    compiled the kernels they met before any had cached them (a fresh-clone suite used 116 s more CPU than a warm
    one, one compilation of every kernel ~40 s: BENCHMARKS.md); compiled first, in two processes, they are
    loaded from the cache by every process after. On a warm cache the parts take a few seconds."""
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    root = Path(__file__).resolve().parent
    if not (root / "_warm_kernels.py").exists():  # this file copied alone, by a test of the lanes
        return {}
    tmp = Path(tempfile.mkdtemp(prefix="graybox-warm-"))
    procs = {}
    for part in WARM_PARTS:
        with open(tmp / part, "w") as err:
            procs[part] = subprocess.Popen([sys.executable, str(root / "_warm_kernels.py"), part], cwd=root.parent,
                                           stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=err)
    ended = {}
    for part, proc in procs.items():
        try:
            rc = proc.wait(timeout=WARM_LIMIT)
        except subprocess.TimeoutExpired:  # a hung part must not hold the suite: killed, and its test fails
            proc.kill()
            proc.wait()
            rc = f"killed past conftest.WARM_LIMIT, {WARM_LIMIT} s"
        ended[part] = (rc, (tmp / part).read_text(encoding="utf-8", errors="replace"))
    return ended


def warm_up(config) -> dict:
    """The warm-up run as the suite began (:func:`warm_kernels`), or one run now (its test run on its own)."""
    if _WARM_UP not in config.stash:
        config.stash[_WARM_UP] = warm_kernels()
    return config.stash[_WARM_UP]


def site_build(config) -> dict:
    """The build started with the suite, or one started now (the docs tests run on their own)."""
    if _SITE_BUILD not in config.stash:
        config.stash[_SITE_BUILD] = start_site_build()
    return config.stash[_SITE_BUILD]


def pytest_runtest_setup(item):
    # the first item of a lane's: the suite's own tests have ended
    if runs_beside(item) and _SUITE_START in item.config.stash and _SUITE_END not in item.config.stash:
        item.config.stash[_SUITE_END] = time.monotonic()


def pytest_terminal_summary(terminalreporter, config):
    """One line: how long the suite's own tests and each lane beside them took (their verdicts' times), so that a
    lane that ends long after the others is seen (:data:`LANES`)."""
    import xml.etree.ElementTree as ET

    runs = config.stash.get(_BESIDE_RUN, None)
    if not runs or _SUITE_END not in config.stash:
        return
    said = [f"the suite's own tests {config.stash[_SUITE_END] - config.stash[_SUITE_START]:.0f} s"]
    for lane, run in runs.items():
        try:
            said.append(f"{lane} {float(ET.parse(run['tmp'] / 'verdicts.xml').getroot()[0].get('time')):.0f} s")
        except (OSError, ET.ParseError, IndexError, TypeError, ValueError):
            said.append(f"{lane} (no time)")
    terminalreporter.write_line("lanes: " + ", ".join(said))


def pytest_unconfigure(config):
    import shutil

    started = [config.stash.get(_SITE_BUILD, None), *config.stash.get(_BESIDE_RUN, {}).values()]
    for run in started:
        if run is None:
            continue
        if run["proc"].poll() is None:  # the suite stopped before its tests waited for it
            _kill_group(run["proc"])
        shutil.rmtree(run["tmp"], ignore_errors=True)
