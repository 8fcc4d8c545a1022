from geofrac.log import Progress, echo, format_seconds


class _Rank:
    def __init__(self, rank):
        self.rank = rank


def test_format_seconds():
    assert format_seconds(0.0123) == "12ms"
    assert format_seconds(4.25) == "4.2s"
    assert format_seconds(185) == "3m05s"
    assert format_seconds(3720) == "1h02m"


def test_only_rank_zero_prints(capsys):
    echo(_Rank(1), "hidden")
    echo(_Rank(0), "shown")
    echo(None, "always")
    assert capsys.readouterr().out == "shown\nalways\n"


def test_progress_reports_steps_and_time_left(capsys):
    progress = Progress(_Rank(0), 4, "job")
    progress.step("a")
    progress.step("b")
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("job [1/4] a") and lines[1].startswith("job [2/4] b")
    assert "steps/s" in lines[1] and "left ~" in lines[1]
    silent = Progress(_Rank(1), 2, "job")
    silent.step()
    assert capsys.readouterr().out == ""
