"""Bad input through the Python API: a Python exception whose message starts with the argument's
name (or, for a bad file, names the file), never a crash and never a result."""
import numpy as np
import pytest

import driftcorr


@pytest.fixture(scope="module")
def parts(synthetic_short):
    sc = driftcorr.load_scenario(synthetic_short)
    return {"trajectory": sc.estimate, "map": sc.map, "anchor": dict(sc.anchor),
            "frame": sc.frame, "mode": sc.mode, "ground_truth": sc.ground_truth}


def call(parts, **changes):
    args = dict(parts, **changes)
    return driftcorr.correct(args.pop("trajectory"), args.pop("map"), args.pop("anchor"), **args)


def with_nan(a, row, col, value=np.nan):
    a = np.array(a, copy=True)
    a[row, col] = value
    return a


def anchor_with(parts, **changes):
    a = dict(parts["anchor"], **changes)
    return {k: v for k, v in a.items() if v is not None}


CASES = [
    ("shape (N, 5)", lambda p: {"trajectory": p["trajectory"][:, :5]}, ValueError,
     r"^trajectory: expected an \(N, 8\) array .* got shape \(\d+, 5\)"),
    ("1-D", lambda p: {"trajectory": p["trajectory"][:, 0]}, ValueError,
     r"^trajectory: expected .* got shape \(\d+,\)"),
    ("NaN", lambda p: {"trajectory": with_nan(p["trajectory"], 2, 1)}, ValueError,
     r"^trajectory: row 2, column 1 \(x\) is NaN"),
    ("inf", lambda p: {"trajectory": with_nan(p["trajectory"], 3, 6, -np.inf)}, ValueError,
     r"^trajectory: row 3, column 6 \(qz\) is infinite"),
    ("two rows", lambda p: {"trajectory": p["trajectory"][:2]}, ValueError,
     r"^trajectory: 2 rows, need at least 3"),
    ("time not increasing", lambda p: {"trajectory": p["trajectory"][[0, 1, 1, 2]]}, ValueError,
     r"^trajectory: row 2: timestamp .* does not increase"),
    ("zero quaternion", lambda p: {"trajectory": np.hstack([p["trajectory"][:, :4],
                                                            np.zeros((len(p["trajectory"]), 4))])},
     ValueError, r"^trajectory: row 0: quaternion .* zero norm"),
    ("strings", lambda p: {"trajectory": [["a", "b", "c", "d"]] * 3}, TypeError,
     r"^trajectory: expected an array of real numbers"),
    ("trajectory None", lambda p: {"trajectory": None}, ValueError, r"^trajectory: missing"),
    ("ground truth rows", lambda p: {"ground_truth": p["ground_truth"][:-1]}, ValueError,
     r"^ground_truth: \d+ rows, the trajectory has \d+"),
    ("ground truth NaN", lambda p: {"ground_truth": with_nan(p["ground_truth"], 5, 3)},
     ValueError, r"^ground_truth: row 5, column 3 \(z\) is NaN"),
    ("map None", lambda p: {"map": None}, ValueError, r"^map: missing"),
    ("map empty", lambda p: {"map": []}, ValueError, r"^map: must list at least one layer"),
    ("map file missing", lambda p: {"map": ["/nonexistent/roads.osm"]}, ValueError,
     r"^map\[0\]: no such file '/nonexistent/roads.osm'"),
    ("map path missing", lambda p: {"map": "/nonexistent/roads.osm"}, ValueError,
     r"^map: no such file"),
    ("map format", lambda p: {"map": [{"path": p["map"][0]["path"], "format": "shp"}]},
     ValueError, r"^map\[0\]\['format'\]: unknown value 'shp'"),
    ("map key", lambda p: {"map": [{"path": p["map"][0]["path"], "fromat": "osm"}]},
     ValueError, r"^map\[0\]: unknown key 'fromat'"),
    ("lifts on roads", lambda p: {"map": [{"path": p["map"][0]["path"], "lifts": [[0, 0, 1, 1]]}]},
     ValueError, r"^map\[0\]\['lifts'\]: only valid on a point-cloud or OctoMap layer"),
    ("lift of 3", lambda p: {"map": [{"path": p["map"][0]["path"], "lifts": [[0, 0, 1]]}]},
     ValueError, r"^map\[0\]\['lifts'\]\[0\]: expected a list of \[x0, y0, x1, y1\] lists"),
    ("anchor None", lambda p: {"anchor": None}, ValueError, r"^anchor: missing"),
    ("anchor no yaw", lambda p: {"anchor": anchor_with(p, yaw_deg=None)}, ValueError,
     r"^anchor\['yaw_deg'\]: missing"),
    ("anchor NaN yaw", lambda p: {"anchor": anchor_with(p, yaw_deg=float("nan"))}, ValueError,
     r"^anchor\['yaw_deg'\]: is not a finite number"),
    ("anchor yaw text", lambda p: {"anchor": anchor_with(p, yaw_deg="north")}, ValueError,
     r"^anchor\['yaw_deg'\]: a number or 'auto'"),
    ("anchor scale", lambda p: {"anchor": anchor_with(p, scale=0)}, ValueError,
     r"^anchor\['scale'\]: must be auto or a number"),
    ("anchor latitude", lambda p: {"anchor": anchor_with(p, lat_deg=91.0)}, ValueError,
     r"^anchor\['lat_deg'\]: must be within \[-90, 90\]"),
    ("anchor both kinds", lambda p: {"anchor": anchor_with(p, crs="EPSG:32632")}, ValueError,
     r"^anchor: give either"),
    ("anchor key", lambda p: {"anchor": anchor_with(p, yaw=3.0)}, ValueError,
     r"^anchor: unknown key 'yaw'"),
    ("anchor no lon", lambda p: {"anchor": anchor_with(p, lon_deg=None)}, ValueError,
     r"^anchor\['lon_deg'\]: missing"),
    ("frame", lambda p: {"frame": "ned"}, ValueError, r"^frame: unknown value 'ned'"),
    ("frame None", lambda p: {"frame": None}, ValueError, r"^frame: missing"),
    ("mode", lambda p: {"mode": "air"}, ValueError, r"^mode: unknown value 'air'"),
    ("solver", lambda p: {"solver": "gradient"}, ValueError, r"^solver: unknown value"),
]


@pytest.mark.parametrize("label,change,error,pattern", CASES, ids=[c[0] for c in CASES])
def test_bad_argument_names_it(parts, label, change, error, pattern):
    with pytest.raises(error, match=pattern):
        call(parts, **change(parts))


def test_path_arguments(parts):
    with pytest.raises(ValueError, match=r"^path: missing"):
        driftcorr.correct_scenario(None)
    with pytest.raises(TypeError, match=r"^path: expected a path"):
        driftcorr.load_scenario(3)
    with pytest.raises(TypeError, match=r"^config: expected a path"):
        call(parts, config=3)
    with pytest.raises(TypeError, match=r"^scenario: expected a path"):
        driftcorr.Stream(3.5)


def test_bad_files_raise_input_error_naming_the_file(parts, tmp_path):
    with pytest.raises(driftcorr.InputError, match=r"/nonexistent/scenario: no such file"):
        driftcorr.correct_scenario("/nonexistent/scenario")
    with pytest.raises(driftcorr.InputError, match=r"/nonexistent/params.yaml"):
        call(parts, config="/nonexistent/params.yaml")
    params = tmp_path / "params.yaml"
    params.write_text("model:\n  map_sigma: 2.0\n")
    with pytest.raises(driftcorr.InputError, match=r"params.yaml:2: model.map_sigma"):
        call(parts, config=params)
    not_osm = tmp_path / "roads.osm"
    not_osm.write_text("this is not XML\n")
    with pytest.raises(driftcorr.InputError, match=str(not_osm)):
        call(parts, map=[str(not_osm)])
    assert issubclass(driftcorr.InputError, ValueError)


def test_metrics_checks_both_arrays(parts):
    en = np.hstack([parts["trajectory"][:, :4], np.zeros((len(parts["trajectory"]), 1))])
    with pytest.raises(ValueError, match=r"^ground_truth_en: \d+ rows, trajectory_en has"):
        driftcorr.metrics(en, en[:-1])
    with pytest.raises(ValueError, match=r"^trajectory_en: expected an \(N, 5\) array"):
        driftcorr.metrics(en[:, :3], en)
    with pytest.raises(ValueError, match=r"^ground_truth_en: row 1, column 2 \(north\) is NaN"):
        driftcorr.metrics(en, with_nan(en, 1, 2))


def test_stream_rejects_bad_poses_and_goes_on(synthetic_short):
    sc = driftcorr.load_scenario(synthetic_short)
    stream = driftcorr.Stream(synthetic_short, synchronous=True)
    est = sc.estimate
    stream.push(est[0])
    with pytest.raises(ValueError, match=r"^pose: expected 8 values .* got shape \(4,\)"):
        stream.push(est[1, :4])
    with pytest.raises(ValueError, match=r"^pose: value 2 \(y\) is NaN"):
        stream.push(with_nan(est[1:2], 0, 2)[0])
    with pytest.raises(ValueError, match=r"^pose: "):
        stream.push(est[0])  # timestamp repeated: rejected by the corrector, stream unchanged
    for row in est[1:5]:
        stream.push(row)
    assert len(stream) == 5
    result = stream.finish()
    assert result.poses == 5
    with pytest.raises(RuntimeError, match=r"finished"):
        stream.push(est[5])
    with pytest.raises(RuntimeError, match=r"already"):
        stream.finish()


def test_stream_arguments(synthetic_short, parts):
    with pytest.raises(ValueError, match=r"^scenario: give a scenario or map"):
        driftcorr.Stream(synthetic_short, map=parts["map"])
    with pytest.raises(ValueError, match=r"^anchor\['yaw_deg'\]: missing"):
        driftcorr.Stream(map=parts["map"], anchor=anchor_with(parts, yaw_deg=None),
                         frame=parts["frame"], mode=parts["mode"])
    with pytest.raises(ValueError, match=r"^map: missing"):
        driftcorr.Stream(anchor=parts["anchor"], frame=parts["frame"], mode=parts["mode"])
    with pytest.raises(driftcorr.InputError, match=r"anchor.yaw_deg"):
        driftcorr.Stream(map=parts["map"], anchor=anchor_with(parts, yaw_deg="auto"),
                         frame=parts["frame"], mode=parts["mode"])


def test_surface_layer_lifts_round_trip(synthetic_short, tmp_path):
    """A point-cloud layer's declared lift shafts come back from load_scenario as given."""
    (tmp_path / "cloud.pcd").write_text("")  # not opened by load_scenario
    yaml = (synthetic_short / "scenario.yaml").read_text()
    yaml = yaml.replace("mode: road2d", "mode: indoor3d")
    yaml = yaml.replace("  yaw_deg: 0.0", "  yaw_deg: 0.0\n  z_m: 0.0")
    yaml = yaml.replace("estimate.tum", str(synthetic_short / "estimate.tum"))
    yaml = yaml.replace("ground_truth.tum", str(synthetic_short / "ground_truth.tum"))
    yaml = yaml.replace("  - path: map.osm\n    format: osm",
                        "  - {path: cloud.pcd, lifts: [[50, 17.5, 52, 19.5], [-1, 0, 1.5, 2]]}")
    (tmp_path / "scenario.yaml").write_text(yaml)
    sc = driftcorr.load_scenario(tmp_path)
    assert sc.mode == "indoor3d"
    assert [list(l) for l in sc.map[0]["lifts"]] == [[50, 17.5, 52, 19.5], [-1, 0, 1.5, 2]]
