"""Review 44d: regressions found in the changes merged this session."""

import os
import shutil
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import graybox as gb
from conftest import two_level_records

TESTS = Path(__file__).resolve().parent

BESIDE_FILE = textwrap.dedent("""
    import os

    import pytest


    @pytest.fixture(scope="module")
    def costly():
        with open(os.environ["R44D_LOG"], "a") as f:
            f.write(("beside" if os.environ.get("GRAYBOX_TESTS_BESIDE") else "suite") + "\\n")
        return 1


    @pytest.fixture
    def broken():
        raise RuntimeError("the fixture broke")


    def test_pass(costly):
        assert costly == 1


    def test_fail():
        assert 1 == 2


    def test_fixture_error(broken):
        pass


    def test_skip():
        pytest.skip("skipped here")


    @pytest.mark.xfail(reason="known")
    def test_xfail():
        assert 0


    @pytest.mark.xfail(reason="strict", strict=True)
    def test_xpass_strict():
        pass


    @pytest.mark.xfail(reason="loose")
    def test_xpass():
        pass
""")


def _outcomes(xml: Path) -> dict[str, str]:
    out = {}
    for case in ET.parse(xml).getroot().iter("testcase"):
        kinds = [c.get("type") if c.tag == "skipped" else c.tag for c in case if c.tag in ("failure", "error",
                                                                                           "skipped")]
        out[case.get("name")] = " ".join(kinds) if kinds else "passed"
    return out


def test_a_file_run_beside_the_suite_reports_each_outcome_as_run_alone_and_sets_up_its_fixtures_once(tmp_path):
    # was: the suite's items of a file run beside it set up their fixtures in the suite too (a module fixture such as
    # test_select_checkpoint's whole select_graybox ran twice, once for nothing), a fixture error there was the
    # suite's own, an xfail was said as a skip and a strict XPASS (a failure) as an xfail
    shutil.copy(TESTS / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_bootstrap.py").write_text(BESIDE_FILE)  # a name BESIDE lists
    log = tmp_path / "log"
    env = {k: v for k, v in os.environ.items() if k != "GRAYBOX_TESTS_BESIDE"}
    env["R44D_LOG"] = str(log)
    subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--basetemp={tmp_path / 'bt'}",
                    f"--junitxml={tmp_path / 'suite.xml'}", "test_bootstrap.py"],
                   cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=300)
    assert _outcomes(tmp_path / "suite.xml") == {
        "test_pass": "passed", "test_fail": "failure", "test_fixture_error": "error", "test_skip": "pytest.skip",
        "test_xfail": "pytest.xfail", "test_xpass_strict": "failure", "test_xpass": "passed"}
    assert log.read_text().split() == ["beside"]


def test_a_test_the_pytest_beside_did_not_run_is_one_error(tmp_path):
    # a test only the suite collects (the pytest beside it has no verdict for it): one error, at its setup, not a
    # second at its teardown
    shutil.copy(TESTS / "conftest.py", tmp_path / "conftest.py")
    (tmp_path / "test_bootstrap.py").write_text(textwrap.dedent("""
        import os

        if not os.environ.get("GRAYBOX_TESTS_BESIDE"):
            def test_only_in_the_suite():
                pass
    """))
    env = {k: v for k, v in os.environ.items() if k != "GRAYBOX_TESTS_BESIDE"}
    subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--basetemp={tmp_path / 'bt'}",
                    f"--junitxml={tmp_path / 'suite.xml'}", "test_bootstrap.py"],
                   cwd=tmp_path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=300)
    assert _outcomes(tmp_path / "suite.xml") == {"test_only_in_the_suite": "error"}


# -- select_graybox's failed members --------------------------------------------------------------------------------

def _records_and_points():
    """Two records of one plant (the first's input at two levels only: λ1 = 1 cannot identify θ on it alone) and
    static points at seven levels."""
    a, b, points = two_level_records(("A", "B"))
    return [a, b], points


def _select(records, points, **kw):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gb.select_graybox(gb.Candidates(1, 1, ne=0, degree=2), records, points, band=1e-2, sizes=[3],
                                 sources=("frols",), include=("1", "u(k-1)^2"), progress=False, **kw)


def test_a_member_failing_only_on_a_fold_is_not_said_to_have_diverged():
    # was: a row's reason counted only the members whose fit on all the identification data failed, so a member whose
    # fold fit failed (its full fit fine, its fold's J_S infinite) was one whose "free run diverged", beside a
    # failed_members column saying its fit failed
    from graybox.experiments._select import _failed_members, _reason

    why = "the fit on 'A' failed: θ at λ1 = 1 (no weight on the static points) is not identifiable"
    res = {"blocks": np.array([[np.inf, 1.0], [np.inf, 2.0]]), "weights": np.array([0.5, 0.5]),
           "jsf": np.array([0.1, 0.2]), "jsf_full": np.array([0.1, 0.2]), "thetas": np.ones((2, 4)),
           "lambdas": np.array([1e-3, 1.0]), "failed": [], "member_failed": ["", why], "warnings": []}
    reason = _reason(res, -1, False, np.inf, 1e-2)
    assert "1 of 2 fits failed" in reason and why in reason
    res["member_failed"] = [why.replace("λ1 = 1", "λ1 = 0.001"), why]
    reason = _reason(res, -1, False, np.inf, 1e-2)
    assert reason.startswith("every member's fit failed") and "diverged" not in reason
    assert _failed_members(res).startswith("2 of 2")


def test_members_failing_for_one_reason_say_it_once(monkeypatch):
    # was: pe_members names a member refused by a constraint check by its λ1 ("λ1 = 0.01: <the check>"), so the
    # column said the same check once per member, each time with another λ1
    from graybox.experiments import _select as sel

    records, points = _records_and_points()
    real = sel.pe_members

    def refusing(st, rec, static, *, lambdas, **kw):
        th, why = real(st, rec, static, lambdas=lambdas, **kw)
        th = th.copy()
        for i in (0, 1):
            th[i] = np.nan
            why[i] = f"λ1 = {lambdas[i]:g}: the check refused it"
        return th, why

    monkeypatch.setattr(sel, "pe_members", refusing)
    lam = [1e-4, 1e-3, 1e-2, 0.5]
    said = _select(records[1:], points, estimator="pe", lambdas=lam, validation=records[0]).table[
        "failed_members"].iloc[0]
    assert said.count("the check refused it") == 1
    assert said.startswith("2 of 4 (λ1 = 0.0001, 0.001)")


# -- parallel_map on Dask ------------------------------------------------------------------------------------------

def _sleeps(x: float) -> float:
    import time

    time.sleep(x)
    return x


@pytest.mark.parametrize("each", [None, lambda i, r: None], ids=["gather", "each"])
def test_ctrl_c_or_an_error_on_a_client_s_cluster_cancels_the_jobs_left(each):
    # was: only a job's error (with each=) cancelled the jobs left; Ctrl-C, or an error while gathering, left them
    # running on the caller's cluster for as long as the traceback held their futures (a notebook keeps it)
    import signal

    # Ctrl-C's handler for this test: a process started in the background of a non-interactive shell inherits SIGINT
    # ignored, and Python then installs none (both tests failed "DID NOT RAISE" in such a run)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _ctrl_c_cancels(each)
    finally:
        signal.signal(signal.SIGINT, before)


def _ctrl_c_cancels(each) -> None:
    import os
    import signal
    import threading

    from distributed import Client

    from graybox.experiments._executors import local_cluster

    with local_cluster(1) as cluster, Client(cluster) as client:
        with gb.experiments.parallel_map(client=client) as pmap:
            client.wait_for_workers(1)
            # a real SIGINT, as Ctrl-C sends: _thread.interrupt_main only flags the main thread, which a blocking wait
            # inside the gather may not notice (once "DID NOT RAISE" under load)
            timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT))
            timer.start()
            with pytest.raises(KeyboardInterrupt):
                pmap(_sleeps, [3.0] * 4, each=each)
            timer.join()
        assert not any(f.status == "pending" for f in client.futures.values())


# -- units of squared errors ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("unit, said", [("mlc", " mlc²"), ("µm", " µm²"), ("m²", " (m²)²"), ("m3", " (m3)²"),
                                        ("kg.m", " (kg.m)²"), ("m/s", " (m/s)²"), ("°C", " °C²"), ("%", " %²"), ("", ""),
                                        ("  ", "")])
def test_a_squared_unit_is_bracketed_unless_it_is_one_word(unit, said):
    # was: only a unit with one of " /*·^()" was bracketed: a model in m² said its J_S in "m²²", one in m3 in "m3²"
    # (m to the 32nd) and one in kg.m in "kg.m²"
    from graybox.core._reprs import squared_unit

    assert squared_unit(unit) == said
