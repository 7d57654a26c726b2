"""The benchmark script runs and writes the documented fields (no timing is asserted)."""

import json
import runpy
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_quick_benchmark_writes_json(tmp_path, monkeypatch):
    output = tmp_path / "bench.json"
    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(sys, "argv", ["run.py", "--quick", "--iterations", "4", "--output", str(output)])
    runpy.run_path(str(ROOT / "bench" / "run.py"), run_name="__main__")
    report = json.loads(output.read_text())
    assert {"ducc0", "finufft", "numpy"} <= set(report["versions"])
    assert [case["domain"] for case in report["cases"]] == ["torus", "torus", "sphere"]
    for case in report["cases"]:
        assert case["seconds_per_iteration"] > 0 and case["raw_transform_seconds_per_iteration"] > 0
        assert {"M", "N", "threads", "backend", "transforms_per_iteration"} <= set(case)
