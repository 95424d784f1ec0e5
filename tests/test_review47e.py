"""Review 47e: regressions found in the changes merged this session."""

import logging
import os
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

from test_grid_executors import _death_cells


def test_a_client_whose_cluster_has_no_worker_yet_is_waited_for_not_ended():
    """An adaptive cluster starts its workers once tasks arrive (from a batch queue, after minutes): a run on its
    client has had no worker *yet*, none *left*, and the watch of 99a34d7 ended it after worker_timeout with
    'no worker ... (all gone, none restarted)' before the first worker came."""
    from distributed import Client, LocalCluster

    from graybox.experiments._executors import DaskCluster

    cluster = LocalCluster(n_workers=0, threads_per_worker=1, processes=True, dashboard_address=":0",
                           silence_logs=logging.ERROR)
    with cluster, Client(cluster) as client:
        cells, data = _death_cells(("LS",))
        late = threading.Timer(3.0, lambda: cluster.scale(1))  # the first worker, after 3 worker_timeouts
        late.start()
        try:
            rows = list(DaskCluster(client=client, worker_timeout=1).run(cells, data))
        finally:
            late.join()
    assert [r["status"] for r in rows] == ["ok"]


def test_a_renamed_attribute_on_the_api_pages_says_it_is_the_old_name_of_the_new(tmp_path):
    """The API pages document every member with a docstring: Structure.inputs, Term.inputs and
    SurfaceClusterMap.inputs were shown as '``inputs = RenamedAttribute("input_names")``', of type 'A class
    attribute ``old`` that reads attribute ``new`` and warns' (RenamedAttribute's own docstring, inherited)."""
    import inspect

    import graybox as gb

    for cls in (gb.Structure, gb.Term, gb.SurfaceClusterMap):
        doc = inspect.getdoc(inspect.getattr_static(cls, "inputs"))
        assert "input_names" in doc and "0.5" in doc and "RenamedAttribute" not in doc, doc
    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text('extensions = ["sphinx.ext.autodoc", "sphinx.ext.napoleon"]\n'
                                 'napoleon_google_docstring = False\nnapoleon_use_ivar = True\n'
                                 'autodoc_default_options = {"members": True}\nsuppress_warnings = ["ref.python"]\n')
    (src / "index.rst").write_text("API\n===\n\n.. autoclass:: graybox.core.Structure\n")
    # in a process of its own, as tests/test_docs.py builds (Sphinx's own deprecation warnings are not ours)
    subprocess.run([sys.executable, "-m", "sphinx", "-q", "-b", "text", str(src), str(tmp_path / "out")],
                   check=True, capture_output=True, cwd=tmp_path, timeout=300,
                   env=dict(os.environ, PYTHONPATH=str(Path(gb.__file__).resolve().parents[1])))  # this graybox
    page = (tmp_path / "out" / "index.txt").read_text(encoding="utf-8")
    entry = page[page.index("\n   inputs\n"):][:400]
    assert "input_names" in entry and "Type:" not in entry and "RenamedAttribute" not in entry, entry


def test_a_pytest_told_it_runs_beside_a_suite_that_is_not_its_parent_does_not_kill_its_process_group(tmp_path):
    """GRAYBOX_TESTS_BESIDE set by hand (to 1, its value before 748b0e3, to run the beside tests in one pytest): the
    pytest took the process 1 for the suite, found it was not its parent, and SIGKILLed its own process group at
    once, a group that is the caller's too when it runs without job control (a CI step's shell, a pipe)."""
    shutil.copy(Path(__file__).resolve().parent / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_slow.py").write_text("import time\n\n\ndef test_slow():\n    time.sleep(3)\n")
    env = dict(os.environ, GRAYBOX_TESTS_BESIDE="1")
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--basetemp={tmp_path / 'bt'}",
                           "test_slow.py"], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300,
                          start_new_session=True)  # its own group: with the fault, only it is killed
    assert done.returncode == 0 and "1 passed" in done.stdout, (done.returncode, done.stdout[-2000:])


def test_a_dask_run_whose_first_submission_fails_leaves_no_worker_watch_running():
    """The first tasks were submitted before the try whose finally closes the worker watch: a run whose first
    submission raised (the store refusing the claim of its first cells, a client gone) left the watch thread
    asking the scheduler once a second for the rest of the process (and the grid-data plugin registered)."""
    import pytest
    from distributed import Client, LocalCluster

    from graybox.experiments._executors import DaskCluster

    def take(cells):
        raise OSError("the store's disk is full")

    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                           silence_logs=logging.ERROR)
    with cluster, Client(cluster) as client:
        cells, data = _death_cells(("LS",))
        with pytest.raises(OSError, match="disk is full"):
            list(DaskCluster(client=client).run(cells, data, take=take))
        assert not [t for t in threading.enumerate() if t.name == "graybox Dask worker watch"]


def test_a_lost_cluster_ends_the_run_even_when_its_watch_empties_what_the_run_was_taking(monkeypatch):
    """The watch emptied the run's as_completed from its own thread (clear()); as_completed's next() looks at its
    queue, then takes from it (a blocking get): a clear() between the two, as a finished task's row is being taken
    when the watch gives up, left the run waiting for ever on an empty queue, the very hang the watch is for. Here
    the run's thread is held between the look and the take (as a busy machine may) while the cluster loses its
    worker."""
    import distributed
    from distributed import Client, LocalCluster

    from graybox.experiments._executors import DaskCluster

    held = threading.Event()

    class Slow(distributed.as_completed):
        def _get_and_raise(self):
            if not held.is_set():  # the first finished task: its worker goes, the watch gives up meanwhile
                held.set()
                time.sleep(4.0)
            return super()._get_and_raise()

    monkeypatch.setattr(distributed, "as_completed", Slow)
    cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0",
                           silence_logs=logging.ERROR)
    with cluster, Client(cluster) as client:
        cells, data = _death_cells(("LS", "CLS", "PE"))
        out: dict = {}

        def drive():
            try:
                out["rows"] = list(DaskCluster(client=client, worker_timeout=1).run(cells, data))
            except Exception as exc:  # noqa: BLE001 - what the run ended with is the test's object
                out["error"] = exc

        t = threading.Thread(target=drive, daemon=True)
        t.start()
        assert held.wait(60)
        cluster.scale(0)
        t.join(timeout=30)
        assert not t.is_alive(), "the run waits for ever on the as_completed its watch emptied"
    assert isinstance(out.get("error"), ConnectionError), out
