import json
import subprocess
import sys

from tests.conftest import BROKEN, JOBS, REPO


def test_check_accepts_the_quickstart(cli):
    code, out, err = cli("check", JOBS / "quickstart.toml")
    assert code == 0 and err == ""
    assert out.startswith("ok: ") and "element p2" in out and "effects: none" in out


def test_run_reports_probes_against_the_exact_solution(cli, tmp_path):
    code, out, _ = cli("run", JOBS / "quickstart.toml", "--out", tmp_path)
    assert code == 0
    assert "probe tip: u = [" in out and "(exact [" in out
    assert "accuracy: ||u - u_exact||_L2" in out
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "ok"


def test_set_override_errors_name_the_key(cli):
    code, _, err = cli("check", JOBS / "quickstart.toml", "--set", "material.E=-1")
    assert code == 2 and "material.E: must be > 0" in err


def test_console_script_exit_codes():
    exe = [sys.executable, "-m", "geofrac.cli"]
    ok = subprocess.run(
        [*exe, "check", "jobs/quickstart.toml"],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
    )
    assert ok.returncode == 0, ok.stderr
    bad = subprocess.run(
        [*exe, "check", str(BROKEN / "nu_half.toml")],
        cwd=REPO,
        capture_output=True,
        text=True,
        check=False,
    )
    assert bad.returncode == 2
    assert bad.stderr.strip().count("\n") == 0 and "material.nu" in bad.stderr
