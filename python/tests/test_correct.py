"""Batch correction through the Python module against the CLI, which runs the same library: the
figures the CLI prints, the trajectory and covariance it writes, and the verdict must agree."""
import numpy as np
import pytest

import driftcorr
from conftest import cli_correct, shared_scenario


def assert_matches_cli(py, cli_run):
    """The module's result equals what `driftcorr correct` printed and wrote (its files hold 6
    decimals for positions, 9 for quaternions, 6 significant digits for covariances)."""
    for label, metrics in (("estimate", py.metrics_before), ("corrected", py.metrics_after)):
        for key in ("ate_m", "final_m", "max_m"):
            assert metrics[key] == pytest.approx(cli_run["figures"][label][key], abs=0.0051), \
                (label, key)
    assert py.verdict == cli_run["verdict"]
    np.testing.assert_allclose(py.corrected, cli_run["corrected"], rtol=0, atol=2e-6)
    cov = cli_run["covariance"]
    np.testing.assert_allclose(py.covariance[:, 0], cov[:, 0], rtol=0, atol=2e-6)
    np.testing.assert_allclose(py.covariance[:, 1:6], cov[:, 1:6], rtol=1e-5, atol=1e-12)
    np.testing.assert_array_equal(py.flags, cov[:, 6].astype(np.uint8))


def test_kitti07_cvo_same_figures_as_cli(cli, workdir):
    scenario = shared_scenario("kitti07_cvo_stereo_geometric")
    py = driftcorr.correct_scenario(scenario)
    assert py.usable and py.status in ("success", "acceptable")
    assert_matches_cli(py, cli_correct(cli, scenario, workdir / "kitti07_cvo"))
    # Against docs/FORMAT.md's judging, recomputed from the returned arrays.
    again = driftcorr.metrics(py.corrected_en, py.ground_truth_en)
    assert again["ate_m"] == pytest.approx(py.metrics_after["ate_m"], rel=1e-12)
    # The drive's scale: the corrected path over the input's (a metric input: global scale 1),
    # with a standard deviation from the covariance.
    path = lambda en: np.linalg.norm(np.diff(en[:, 1:3], axis=0), axis=1).sum()
    assert py.global_scale == 1.0
    assert py.drive_scale == pytest.approx(path(py.corrected_en) / path(py.estimate_en), rel=1e-9)
    assert 0.0 < py.drive_scale_sd < 0.05


def test_synthetic_same_as_cli_and_better_than_estimate(cli, synthetic, workdir):
    py = driftcorr.correct_scenario(synthetic)
    assert_matches_cli(py, cli_correct(cli, synthetic, workdir / "synthetic"))
    # The drift injected by the generator must come out: the README's run gives 33.95 m -> 1.91 m.
    assert py.metrics_after["ate_m"] < 0.2 * py.metrics_before["ate_m"]


def test_layouts(synthetic_short):
    py = driftcorr.correct_scenario(synthetic_short)
    sc = driftcorr.load_scenario(synthetic_short)
    n = sc.estimate.shape[0]
    assert sc.estimate.shape == (n, 8) and sc.ground_truth.shape == (n, 8)
    assert py.corrected.shape == (n, 8) and py.corrected.dtype == np.float64
    assert py.corrected_en.shape == (n, 5) and py.estimate_en.shape == (n, 5)
    assert py.covariance.shape == (n, 8) and py.covariance_status == "ok"
    assert py.flags.shape == (n,) and py.flags.dtype == np.uint8
    np.testing.assert_array_equal(py.corrected[:, 0], sc.estimate[:, 0])
    np.testing.assert_array_equal(py.covariance[:, 0], sc.estimate[:, 0])
    np.testing.assert_allclose(np.linalg.norm(py.corrected[:, 4:8], axis=1), 1.0, atol=1e-12)
    assert py.verdict in ("ok", "degraded", "failed") and isinstance(py.reasons, list)


def test_arrays_in_memory_give_the_scenario_result(synthetic_short):
    """correct() on the parts load_scenario returns (arrays, map, anchor) runs the same
    correction as correct_scenario() on the folder."""
    sc = driftcorr.load_scenario(synthetic_short)
    from_folder = driftcorr.correct_scenario(synthetic_short)
    from_arrays = driftcorr.correct(sc.estimate, sc.map, sc.anchor, frame=sc.frame, mode=sc.mode,
                                    ground_truth=sc.ground_truth, name=sc.name)
    # The arrays carry the quaternions once more through normalisation: last-bit differences.
    np.testing.assert_allclose(from_arrays.corrected, from_folder.corrected, rtol=0, atol=1e-9)
    np.testing.assert_allclose(from_arrays.covariance, from_folder.covariance, rtol=1e-6, atol=1e-12)
    for key, value in from_folder.metrics_after.items():
        assert from_arrays.metrics_after[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key
    assert from_arrays.verdict == from_folder.verdict
    # Without ground truth there are no metrics, and the correction is the same.
    blind = driftcorr.correct(sc.estimate, sc.map[0]["path"], sc.anchor, frame=sc.frame,
                              mode=sc.mode)
    assert blind.metrics_after is None and blind.ground_truth_en is None
    np.testing.assert_allclose(blind.corrected, from_folder.corrected, rtol=0, atol=1e-9)


def test_trajectory_without_orientation(synthetic_short):
    """(N, 4) `t x y z` in, (N, 8) out: headings come from the steps, and the orientation written
    is the corrected heading alone (as the CLI writes it)."""
    sc = driftcorr.load_scenario(synthetic_short)
    c = driftcorr.correct(sc.estimate[:, :4], sc.map, sc.anchor, frame=sc.frame, mode=sc.mode,
                          ground_truth=sc.ground_truth[:, :4])
    assert c.usable and c.corrected.shape == (len(sc.estimate), 8)
    assert c.corrected_en.shape == (len(sc.estimate), 5)
    assert c.metrics_after["ate_m"] < c.metrics_before["ate_m"]


def test_paper_solver_is_selectable(synthetic_short):
    paper = driftcorr.correct_scenario(synthetic_short, solver="paper")
    ours = driftcorr.correct_scenario(synthetic_short)
    assert paper.corrected.shape == ours.corrected.shape
    assert not np.array_equal(paper.corrected, ours.corrected)
