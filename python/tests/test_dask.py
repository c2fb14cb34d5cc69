"""The Dask recipe (python/examples/dask_correct.py) on a LocalCluster of two worker processes:
a directory of scenarios mapped over the cluster gives, per scenario, the figures the CLI prints
for it."""
import importlib.util
import os
import sys
from pathlib import Path

import pytest

from conftest import cli_correct

distributed = pytest.importorskip("distributed", reason="python3-distributed is not installed")
cloudpickle = pytest.importorskip("cloudpickle")

RECIPE = Path(__file__).resolve().parents[1] / "examples" / "dask_correct.py"


def load_recipe():
    spec = importlib.util.spec_from_file_location("dask_correct", RECIPE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    # The workers cannot import the recipe by name: ship its functions by value.
    cloudpickle.register_pickle_by_value(module)
    return module


def test_recipe_on_local_cluster_matches_cli(cli, synthetic, workdir, tmp_path):
    recipe = load_recipe()
    drives = tmp_path / "drives"
    drives.mkdir()
    (drives / "synthetic-road").symlink_to(synthetic)
    shared = Path(os.environ.get("DRIFTCORR_SHARED_DATASETS", "/nonexistent"))
    kitti07 = shared / "kitti07_cvo_stereo_geometric"
    if (kitti07 / "scenario.yaml").is_file():
        (drives / kitti07.name).symlink_to(kitti07)
    (drives / "not-a-scenario").mkdir()

    paths = recipe.find_scenarios(drives, mode="road2d")
    assert [Path(p).name for p in paths] == sorted(p.name for p in drives.iterdir()
                                                   if p.name != "not-a-scenario")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        results = recipe.correct_all(client, paths + [str(drives / "not-a-scenario")])

    assert "error" in results[-1] and "scenario.yaml" in results[-1]["error"]
    for r in results[:-1]:
        expected = cli_correct(cli, r["path"], workdir / ("dask_" + Path(r["path"]).name))
        assert r["verdict"] == expected["verdict"]
        for label, metrics in (("estimate", r["before"]), ("corrected", r["after"])):
            for key in ("ate_m", "final_m", "max_m"):
                assert metrics[key] == pytest.approx(expected["figures"][label][key], abs=0.0051)
    assert "synthetic-road" in recipe.format_table(results)
