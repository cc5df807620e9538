"""The suite never skips (issue 42): tests/conftest.py turns every skip and xfail into a failure that names the
install to fix, and this test plants each kind in a throw-away suite that uses the same conftest."""

from __future__ import annotations

from pathlib import Path

pytest_plugins = ["pytester"]

PLANTED = '''
import pytest

def test_skip_call():
    pytest.skip("corpus missing")

@pytest.mark.skipif(True, reason="extra missing")
def test_skipif():
    pass

def test_xfail_call():
    pytest.xfail("known")

@pytest.mark.xfail(reason="known, marked")
def test_xfail_mark():
    assert False

def test_passes():
    pass
'''


def test_every_kind_of_skip_fails_and_says_what_to_install(pytester):
    pytester.makeconftest((Path(__file__).parent / "conftest.py").read_text())
    pytester.makepyfile(test_planted=PLANTED, test_module_skip='import pytest\npytest.importorskip("no_such_extra")\n'
                                                               "def test_never_runs():\n    pass\n")
    run = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-n", "0", "--continue-on-collection-errors")
    outcomes = run.parseoutcomes()
    assert "skipped" not in outcomes and "xfailed" not in outcomes, outcomes
    assert outcomes.get("passed") == 1, outcomes
    # the call-time skips and xfails fail; the skipif (at setup) and the import-time skip are errors
    assert outcomes.get("failed", 0) + outcomes.get("errors", outcomes.get("error", 0)) == 5, outcomes
    text = run.stdout.str()
    assert text.count('pip install -e ".[test]"') >= 5 and "no_such_extra" in text and "corpus missing" in text
