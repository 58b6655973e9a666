"""studies.sweep: the grid's records serially and on a Dask cluster (identical), clear errors,
CSV output that never overwrites unasked."""

import csv

import pytest

from tensor_cosdi import studies


def _square(x, y):
    return {"value": x * x + y}


def test_serial_sweep_records_every_combination_in_order():
    rows = studies.sweep({"x": [1, 2, 3], "y": [0, 10]}, _square, progress=False)
    assert [(r["x"], r["y"], r["value"]) for r in rows] == [
        (1, 0, 1), (1, 10, 11), (2, 0, 4), (2, 10, 14), (3, 0, 9), (3, 10, 19),
    ]  # fmt: skip


def test_dask_sweep_equals_the_serial_one():
    distributed = pytest.importorskip("dask.distributed")
    grid = {"system": ["sd_cassi", "cs2li"], "method": ["lsq", "gap_tv"], "snr_db": [30.0]}
    opts = {"shape": [(16, 16)], "n_bands": [4]}
    serial = studies.sweep({**grid, **opts}, studies.reconstruction_run, progress=False)
    with distributed.Client(processes=False, n_workers=2, threads_per_worker=1) as client:
        par = studies.sweep({**grid, **opts}, studies.reconstruction_run, client=client,
                            progress=False)  # fmt: skip
    assert len(par) == 4
    for a, b in zip(serial, par):
        assert (a["system"], a["method"]) == (b["system"], b["method"])
        assert a["psnr"] == pytest.approx(b["psnr"], abs=1e-9)
    cs2li = next(r for r in par if r["system"] == "cs2li")
    assert any(k.startswith("depth_") for k in cs2li)  # the depth channel is scored too


def test_sweep_errors_and_csv(tmp_path):
    with pytest.raises(ValueError, match="non-empty dict"):
        studies.sweep({}, _square)
    with pytest.raises(ValueError, match="sequence of values"):
        studies.sweep({"x": "abc"}, _square)
    with pytest.raises(ValueError, match="overwrite the parameters"):
        studies.sweep({"x": [1], "value": [2]}, lambda x, value: {"value": 3}, progress=False)
    with pytest.raises(TypeError, match="must return a dict"):
        studies.sweep({"x": [1]}, lambda x: x, progress=False)
    for grid, kw, message in (
        ({"x": {"a": 1}}, {}, "grid\\['x'\\] must be a sequence of values"),  # not its keys
        ({"x": {1, 2}}, {}, "must be a sequence of values"),  # a set has no fixed order
        ({3: [1]}, {}, "grid keys must be parameter names \\(identifiers\\), got 3"),
        ({"x": [1]}, {"progress": "no"}, "progress must be True or False"),
        ({"x": [1]}, {"client": 3}, 'client must be None, "local", a scheduler address'),
    ):
        with pytest.raises(ValueError, match=message):
            studies.sweep(grid, lambda x: {"v": x}, **kw)
    # an iterator's values are read once: the sweep runs them, not nothing
    rows = studies.sweep({"x": iter([1, 2]), "y": [0]}, _square, progress=False)
    assert [r["value"] for r in rows] == [1, 4]
    rows = studies.sweep({"x": [1, 2], "y": [5]}, _square, progress=False)
    path = studies.write_csv(rows, tmp_path / "t.csv")
    with open(path) as f:
        back = list(csv.DictReader(f))
    assert back == [{"x": "1", "y": "5", "value": "6"}, {"x": "2", "y": "5", "value": "9"}]
    with pytest.raises(FileExistsError):
        studies.write_csv(rows, path)


def test_local_client_pins_threads_and_keeps_glibcs_mmap_threshold():
    """``sweep(client="local")``'s cluster: single-threaded workers whose environment has the
    BLAS pins but not Dask's MALLOC_TRIM_THRESHOLD_ (page faults: see ``local_client``)."""
    pytest.importorskip("dask.distributed")
    import os

    with studies.local_client(1) as client:
        env = client.run(
            lambda: {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "MALLOC_TRIM_THRESHOLD_")}
        )
        assert list(env.values()) == [{"OMP_NUM_THREADS": "1", "MALLOC_TRIM_THRESHOLD_": None}]
        rows = studies.sweep({"x": [1, 2], "y": [5]}, _square, client=client, progress=False)
    assert [r["value"] for r in rows] == [6, 9]
    assert [r["value"] for r in studies.sweep({"x": [3], "y": [0]}, _square, client="local",
                                             progress=False)] == [9]  # fmt: skip
    with pytest.raises(ValueError, match="n_workers"):
        with studies.local_client(0):
            pass


def test_a_grid_axis_without_values_and_options_for_no_method_are_errors():
    with pytest.raises(ValueError, match=r"grid\['x'\] holds no values"):
        studies.sweep({"x": [], "y": [1]}, _square, progress=False)
    p = studies.make_problem("sd_cassi", shape=(8, 8), n_bands=4)
    with pytest.raises(ValueError, match="at least one method"):
        studies.compare(p, ())
    with pytest.raises(ValueError, match=r"options given for \['otd'\]"):
        studies.compare(p, ("gap_tv",), options={"otd": {"lam": 1.0}})
    (row,) = studies.compare(p, "gap_tv", options={"gap_tv": {"max_iter": 2}})
    assert row["method"] == "gap_tv" and row["iterations"] == 2
