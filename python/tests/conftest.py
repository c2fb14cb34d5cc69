"""Shared fixtures of the Python tests. ctest (python/CMakeLists.txt) sets the environment:
PYTHONPATH (the built package), DRIFTCORR_CLI (the driftcorr binary the results are compared
with), DRIFTCORR_MAKE_ROAD_SCENARIO (the synthetic scenario generator),
DRIFTCORR_SHARED_DATASETS (the real scenarios, ../shared/datasets) and DRIFTCORR_TEST_TMPDIR.
A test whose input is missing is skipped and says which."""
import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest


def _env_path(name):
    value = os.environ.get(name)
    return Path(value) if value else None


def shared_scenario(name):
    """A real scenario folder, or a skip naming what is missing."""
    root = _env_path("DRIFTCORR_SHARED_DATASETS")
    if root is None:
        pytest.skip("DRIFTCORR_SHARED_DATASETS is not set (ctest sets it)")
    path = root / name
    if not (path / "scenario.yaml").is_file():
        pytest.skip(f"{path} is absent (the real scenarios live in ../shared/datasets)")
    return path


@pytest.fixture(scope="session")
def cli():
    path = _env_path("DRIFTCORR_CLI")
    if path is None or not path.is_file():
        pytest.skip("DRIFTCORR_CLI is not set or absent (built with BUILD_EXAMPLES; ctest sets it)")
    return path


@pytest.fixture(scope="session")
def workdir(tmp_path_factory):
    root = _env_path("DRIFTCORR_TEST_TMPDIR")
    if root is None:
        return tmp_path_factory.mktemp("driftcorr")
    root.mkdir(parents=True, exist_ok=True)
    return root


def _generate(tmp_path_factory, name, *args):
    generator = _env_path("DRIFTCORR_MAKE_ROAD_SCENARIO")
    if generator is None or not generator.is_file():
        pytest.skip("DRIFTCORR_MAKE_ROAD_SCENARIO is not set (ctest sets it)")
    out = tmp_path_factory.mktemp(name)
    subprocess.run([str(generator), str(out), *args], check=True, capture_output=True)
    return out


@pytest.fixture(scope="session")
def synthetic(tmp_path_factory):
    """The default synthetic road scenario (deterministic seed, 4201 poses)."""
    return _generate(tmp_path_factory, "synthetic-road")


@pytest.fixture(scope="session")
def synthetic_short(tmp_path_factory):
    """The same generator's first 120 s (1201 poses), where a test needs several runs."""
    return _generate(tmp_path_factory, "synthetic-road-short", "--duration-s", "120")


_ROW = re.compile(r"^\s+(estimate|corrected)\s+ATE\s+(\S+) m\s+final\s+(\S+) m\s+max\s+(\S+) m",
                  re.M)


def cli_correct(cli, scenario, out_dir):
    """Runs `driftcorr correct` and returns its printed figures and written files: ATE / final /
    max (2 decimals, as printed), the verdict, the corrected TUM rows and the covariance rows."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    tum, cov = out_dir / "corrected.tum", out_dir / "covariance.txt"
    for f in (tum, cov):
        f.unlink(missing_ok=True)
    proc = subprocess.run([str(cli), "correct", str(scenario), "-o", str(tum), "--covariance",
                           str(cov), "--on-failure", "write", "--quiet"],
                          capture_output=True, text=True)
    assert proc.returncode in (0, 3), proc.stderr
    figures = {m.group(1): {"ate_m": float(m.group(2)), "final_m": float(m.group(3)),
                            "max_m": float(m.group(4))} for m in _ROW.finditer(proc.stdout)}
    verdict = re.search(r"^verdict\s+(\S+)", proc.stdout, re.M).group(1)
    return {"figures": figures, "verdict": verdict, "stdout": proc.stdout,
            "corrected": np.loadtxt(tum, ndmin=2) if tum.exists() else None,
            "covariance": np.loadtxt(cov, ndmin=2) if cov.exists() else None}
