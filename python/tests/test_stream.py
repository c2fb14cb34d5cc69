"""The online corrector through Python against `driftcorr stream --replay --sync` (both solve
inside push, so both are deterministic): the causal pose of every push and the smoothed
trajectory of finish must be what the CLI writes."""
import subprocess

import numpy as np

import driftcorr


def test_stream_same_as_cli(cli, synthetic_short, workdir):
    smoothed_file = workdir / "stream_smoothed.tum"
    smoothed_file.unlink(missing_ok=True)
    proc = subprocess.run([str(cli), "stream", str(synthetic_short), "--replay", "--sync", "-q",
                           "--status-column", "--smoothed-out", str(smoothed_file)],
                          capture_output=True, text=True, check=True)
    cli_lines = np.loadtxt(proc.stdout.splitlines(), ndmin=2)
    cli_causal, cli_status = cli_lines[:, :8], cli_lines[:, 8:]

    sc = driftcorr.load_scenario(synthetic_short)
    # --replay feeds the estimate as TUM text (6 decimals, quaternions 9): the same input here.
    replayed = np.hstack([np.round(sc.estimate[:, :4], 6), np.round(sc.estimate[:, 4:], 9)])
    stream = driftcorr.Stream(synthetic_short, synchronous=True)
    pushed = [stream.push(row) for row in replayed]
    causal = np.array([p.pose for p in pushed])
    result = stream.finish()

    assert causal.shape == cli_causal.shape == sc.estimate.shape
    np.testing.assert_allclose(causal, cli_causal, rtol=0, atol=2e-6)
    # The status column: age in epochs and seconds, fresh, the horizontal covariance, the doubt.
    nan = float("nan")
    status = np.array([[p.correction_age_epochs, p.correction_age_s, p.fresh,
                        *(p.covariance[:3] if p.covariance is not None else (nan, nan, nan)),
                        p.doubt] for p in pushed])
    assert all(p.covariance is None or p.covariance.shape == (7,) for p in pushed)
    assert sum(p.covariance is not None for p in pushed) > len(pushed) // 2
    np.testing.assert_array_equal(status[:, [0, 2, 6]], cli_status[:, [0, 2, 6]])
    np.testing.assert_allclose(status[:, 1], cli_status[:, 1], rtol=0, atol=6e-4)
    np.testing.assert_allclose(status[:, 3:6], cli_status[:, 3:6], rtol=1e-5, atol=1e-12)
    assert result.usable and result.poses == len(sc.estimate)
    np.testing.assert_allclose(result.corrected, np.loadtxt(smoothed_file), rtol=0, atol=2e-6)
    assert result.covariance.shape == (len(sc.estimate), 8)
    assert result.verdict == "ok", result.reasons
    # A metric stream: no scale searched.
    assert result.global_scale is None and result.outputs_before_scale == 0


def test_stream_from_map_and_anchor(synthetic_short):
    """The same stream set up from the parts instead of the folder."""
    sc = driftcorr.load_scenario(synthetic_short)
    a = driftcorr.Stream(synthetic_short, synchronous=True)
    b = driftcorr.Stream(map=sc.map, anchor=sc.anchor, frame=sc.frame, mode=sc.mode,
                         synchronous=True)
    for row in sc.estimate[:300]:
        pa, pb = a.push(row), b.push(row)
        np.testing.assert_array_equal(pa.pose, pb.pose)
        np.testing.assert_array_equal(pa.pose_en, pb.pose_en)
    assert a.finish().usable and b.finish().usable


def test_threaded_stream_finishes(synthetic_short):
    """The default (threaded) mode: push returns at once, finish waits for the worker."""
    sc = driftcorr.load_scenario(synthetic_short)
    stream = driftcorr.Stream(synthetic_short)
    out = [stream.push(row) for row in sc.estimate[:800]]
    assert [p.index for p in out] == list(range(800))
    # Why a pose may be wrong, as the stream's status column says it: bits 1 to 128.
    assert all(isinstance(p.doubt, int) and 0 <= p.doubt <= 255 for p in out)
    assert all(bool(p.doubt & 1) == p.outside_map for p in out)
    result = stream.finish()
    assert result.usable and result.corrected.shape == (800, 8)


def test_stream_pushed_from_two_threads_takes_each_pose_once(synthetic_short):
    """Two threads push the same poses: each pose is taken once (the other thread's copy is
    refused as not newer), indices are unique and in the order of the timestamps, and finish()
    holds exactly the poses taken."""
    import threading

    sc = driftcorr.load_scenario(synthetic_short)
    rows = sc.estimate[:600]
    stream = driftcorr.Stream(synthetic_short)  # threaded: push is quick, the race window wide
    taken, refused = [], []
    lock = threading.Lock()

    def pusher():
        for row in rows:
            try:
                out = stream.push(row)
            except ValueError as e:
                with lock:
                    refused.append(str(e))
                continue
            with lock:
                taken.append((out.index, row[0]))

    threads = [threading.Thread(target=pusher) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(taken) <= len(rows), "a pose was taken twice"
    indices = sorted(i for i, _ in taken)
    assert indices == list(range(len(taken))), "duplicate or missing indices"
    by_index = [t for _, t in sorted(taken)]
    assert all(b > a for a, b in zip(by_index, by_index[1:])), "indices not in timestamp order"
    assert len(taken) + len(refused) == 2 * len(rows)
    result = stream.finish()
    assert result.poses == len(taken)
    assert np.all(np.diff(result.corrected[:, 0]) > 0)
