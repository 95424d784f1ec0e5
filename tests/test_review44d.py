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
        out[case.get("name")] = kinds[0] if kinds else "passed"
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
