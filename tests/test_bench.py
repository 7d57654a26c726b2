"""The benchmark script runs and writes the documented fields (no timing is asserted)."""

import collections
import importlib
import json
import os
import runpy
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_quick_benchmark_writes_json(tmp_path, monkeypatch):
    output = tmp_path / "bench.json"
    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(sys, "argv", ["run.py", "--quick", "--iterations", "4", "--output", str(output)])
    runpy.run_path(str(ROOT / "bench" / "run.py"), run_name="__main__")
    report = json.loads(output.read_text())
    assert {"ducc0", "finufft", "numpy"} <= set(report["versions"])
    cases = [case for case in report["cases"] if not case.get("scale") and not case.get("video")]
    scale = [case for case in report["cases"] if case.get("scale")]
    (video,) = [case for case in report["cases"] if case.get("video")]
    assert video["M"] == 500 and video["frames"] == 6 and video["seconds_per_warm_frame"] > 0
    assert video["seconds_per_cold_run"] > 0 and 0 < video["energy_over_cold"]["max"] < 1.5
    assert [case["domain"] for case in cases] == ["torus"] * 3 + ["sphere"] * 4
    assert [case["near_field"] for case in cases] == [True, False, True, True, False, True, False]
    torus, design = scale
    assert torus["M"] == 20000 and torus["seconds_per_iteration"] > 0 and torus["peak_memory_mb"] > 0
    assert design["status"] == "converged" and design["iterations_to_target"] > 0 and design["seconds_to_target"] > 0
    for case in cases:
        assert case["seconds_per_iteration"] > 0 and case["raw_transform_seconds_per_iteration"] > 0
        assert case["seconds_per_iteration_at_start"] > 0
        assert {"M", "N", "threads", "backend", "transforms_per_iteration", "peak_memory_mb"} <= set(case)
        assert (case["near_field_pairs"] > 0) == case["near_field"]


def load_bench_module(name):
    """A script of ``bench/`` as a module."""
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(ROOT / "bench"))


def test_quality_inputs_have_the_documented_properties(tmp_path):
    import numpy as np

    quality = load_bench_module("quality")
    made = {name: make() for inputs in quality.SETS.values() for name, _, _, make in inputs}
    assert made["strip6x1"].shape == (200, 1200) and made["strip4x1"].shape == (300, 1200)
    for name in ("silhouette", "silhouette2"):
        assert set(np.unique(made[name])) == {0.0, 1.0}
    assert abs(np.mean(made["dark"]) - 0.2) < 1e-6
    assert abs(np.mean(made["dark2"]) - 0.15) < 1e-6
    assert abs(made["bump8"].min() - 0.04) < 1e-9
    assert made["bump8"].max() > 0.99 and abs(made["bump5"].min() - 0.02) < 1e-9
    for name in ("relief3", "relief4"):
        assert made[name].min() == 0 and made[name].max() == 1
    # Crops render the densest region: i.i.d. points of the bump land mostly inside the zoomed window.
    from stipple.sphere import CellMap

    points = CellMap(made["bump8"]).sample(np.random.default_rng(0), 3000)
    crop = np.asarray(quality.sphere_crop(points, made["bump8"]))
    assert crop.shape == (quality.CROP_PIXELS,) * 2 and 0 < np.mean(crop < 128) < 0.5
    unit = np.random.default_rng(1).random((2000, 2))
    crop = np.asarray(quality.torus_crop(unit, made["strip6x1"]))
    assert crop.shape == (quality.CROP_PIXELS,) * 2 and 0 < np.mean(crop < 128) < 0.5


def test_paired_commands_run_the_version_named_not_a_checkout_in_the_current_folder(tmp_path, monkeypatch):
    """``python -m stipple`` puts its current directory first: started beside another checkout's ``stipple`` it
    would run that one. The commands run in the ``--out`` folder, and a relative program is made absolute."""
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        import paired
    finally:
        sys.path.remove(str(ROOT / "bench"))
    decoy = tmp_path / "checkout"
    (decoy / "stipple").mkdir(parents=True)
    (decoy / "stipple" / "__init__.py").write_text("")
    (decoy / "stipple" / "__main__.py").write_text("raise SystemExit(3)\n")
    monkeypatch.chdir(decoy)
    program = os.path.relpath(sys.executable, decoy)
    results = paired.main(
        ["--new", f"{program} -m stipple", "--cases", "smoke", "--repeats", "1", "--out", str(tmp_path / "a" / "b")]
        + ["--output", str(tmp_path / "paired.json")]
    )
    assert results["smoke"]["versions"]["new"]["returncodes"] == [0]


def test_paired_whole_commands_report_both_versions_and_their_quality(tmp_path):
    """Two versions (here the same command twice) and a variant of the new one (its default seed given) alternated:
    wall time, peak memory, iterations and the same measures for all; identical runs give identical quality."""
    sys.path.insert(0, str(ROOT / "bench"))
    try:
        import paired
    finally:
        sys.path.remove(str(ROOT / "bench"))
    command = f"{sys.executable} -m stipple"
    output = tmp_path / "paired.json"
    results = paired.main(
        ["--old", command, "--cases", "smoke", "--repeats", "2", "--out", str(tmp_path), "--output", str(output)]
        + ["--variant", "seeded=--seed 0"]
    )
    assert json.loads(output.read_text()) == results
    entry = results["smoke"]
    old, new, seeded = (entry["versions"][label] for label in ("old", "new", "seeded"))
    assert seeded["command"].endswith("--seed 0")
    for version in (old, new, seeded):
        assert len(version["seconds"]) == 2 and version["median_seconds"] > 0 and version["peak_gib"] > 0
        assert version["returncodes"] == [0, 0] and all(count > 0 for count in version["iterations"])
        quality = version["quality"]
        assert len(quality["psnr_exact"]) == 3 and 0 < quality["p01"] < 1.2 and quality["untruncated_energy"] > 0
        assert 0 <= quality["picture_sigma4_rmse"] < 0.1
    assert old["quality"] == new["quality"] == seeded["quality"] and entry["ratio_new_over_old"] > 0
    assert len(entry["ratios_per_round"]) == len(entry["ratios_seeded_per_round"]) == 2


def test_phase_clocks_count_a_call_handed_to_other_threads_once(monkeypatch):
    """A clocked method that runs clocked methods of the same label on other threads (as the residue-split
    transforms do) adds its own wall time once, not its parts' as well."""
    from concurrent.futures import ThreadPoolExecutor

    phases = load_bench_module("phases")

    class Transform:
        def part(self):
            time.sleep(0.05)

        def whole(self):
            with ThreadPoolExecutor(2) as pool:
                list(pool.map(lambda _: self.part(), range(2)))

    monkeypatch.setattr(phases, "CLOCKS", collections.defaultdict(float))
    monkeypatch.setattr(phases, "CALLS", collections.defaultdict(int))
    for name in ("part", "whole"):
        phases.clocked(Transform, name, "transforms", monkeypatch.setattr)
    start = time.perf_counter()
    Transform().whole()
    elapsed = time.perf_counter() - start
    assert phases.CALLS["transforms"] == 1
    assert 0.05 <= phases.CLOCKS["transforms"] <= elapsed
    Transform().part()
    assert phases.CALLS["transforms"] == 2


def test_phases_of_a_one_thread_command_are_disjoint(monkeypatch):
    """On one thread the clocks nest as documented: no phase is negative (the transforms inside the discrepancy's
    time, the discrepancy and the pairs inside the command's), and every phase ran."""
    phases = load_bench_module("phases")
    record = phases.measure(ROOT / "samples" / "astronaut256.png", 3000, patch=monkeypatch.setattr)
    seconds = record["seconds"]
    # ``rest`` is the command less the discrepancy and the pairs: positive only if neither was counted twice.
    assert all(seconds[name] > 0 for name in seconds), seconds
    assert record["full_searches"] >= 1 and record["calls"]["transforms"] > record["calls"]["discrepancy"] / 2
