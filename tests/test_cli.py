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


def test_a_second_run_into_a_completed_directory_is_refused_before_any_work(cli, tmp_path):
    out = tmp_path / "out"
    assert cli("run", JOBS / "quickstart.toml", "--out", out)[0] == 0
    first = (out / "summary.json").read_bytes()
    code, stdout, err = cli("run", JOBS / "quickstart.toml", "--out", out)
    assert code == 2
    assert "holds a completed run" in err and "--overwrite" in err and "--resume" in err
    assert stdout == ""  # refused before the banner: nothing ran
    assert (out / "summary.json").read_bytes() == first


def test_overwrite_replaces_the_results_only_when_the_new_run_succeeds(cli, tmp_path):
    out = tmp_path / "out"
    assert cli("run", JOBS / "cantilever.toml", "--out", out)[0] == 0
    first = json.loads((out / "summary.json").read_text())
    # a run that fails after it started (singular: no support in y) leaves the old results
    singular = ("--set", "bc.0.value=[0.0]", "--set", 'bc.0.components=["x"]')
    code, _, err = cli("run", JOBS / "cantilever.toml", "--out", out, "--overwrite", *singular)
    assert code == 1 and "singular" in err
    assert json.loads((out / "summary.json").read_text()) == first
    # a stiffer material: the replaced results are the new run's (half the deflection)
    stiff = ("--set", "material.E=200.0")
    code, _, err = cli("run", JOBS / "cantilever.toml", "--out", out, "--overwrite", *stiff)
    assert code == 0, err
    again = json.loads((out / "summary.json").read_text())
    assert again["status"] == "ok"
    name = next(iter(first["results"]["probes"]))
    old, new = first["results"]["probes"][name][1], again["results"]["probes"][name][1]
    assert abs(new - old / 2) < 1e-9 * abs(old)


def test_an_output_directory_that_is_a_file_exits_2_before_the_banner(cli, tmp_path):
    (tmp_path / "taken").write_text("not a directory")
    code, stdout, err = cli("run", JOBS / "quickstart.toml", "--out", tmp_path / "taken")
    assert code == 2 and "--out: " in err and "is not a directory" in err
    assert stdout == ""


def test_resume_without_a_checkpoint_exits_2_before_the_banner(cli, tmp_path):
    code, stdout, err = cli("run", JOBS / "quickstart.toml", "--out", tmp_path, "--resume")
    assert code == 2 and "no complete checkpoint" in err and stdout == ""
