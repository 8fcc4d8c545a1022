import json

import numpy as np
import pytest

from geofrac.bench.report import fit_rate, format_table, plot_accuracy_cost
from geofrac.io.summary import write_json


def test_fit_rate_recovers_a_known_power_law():
    nodes = np.array([205, 306, 427, 568, 729])
    errors = 3.0 * np.sqrt(nodes) ** -2.5
    assert fit_rate(nodes, errors) == pytest.approx(2.5, rel=1e-12)
    assert np.isnan(fit_rate([10], [1.0]))


def test_table_and_plot_and_json(tmp_path):
    records = [
        {"element": "a", "dofs": 10, "error_u": 1.0, "error_energy": 2.0, "time_total_s": 0.1},
        {"element": "a", "dofs": 40, "error_u": 0.25, "error_energy": 1.0, "time_total_s": 0.3},
    ]
    table = format_table(
        records, [("element", "el", "s"), ("dofs", "DOFs", "d"), ("error_u", "e", ".1e")]
    )
    lines = table.splitlines()
    assert len(lines) == 4 and "1.0e+00" in lines[2] and "2.5e-01" in lines[3]
    plot_accuracy_cost(records, tmp_path / "p.png", "t")
    assert (tmp_path / "p.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    write_json(tmp_path / "sub" / "r.json", {"records": records})
    assert json.loads((tmp_path / "sub" / "r.json").read_text())["records"] == records
