"""pendula.sweep and pendula.merge: the CLI's bytes (lanes and scalar path), shards merged
either way between Python and the CLI, merge's refusals, thread-count independence, and
pendula.ensemble's scalar path."""

import json
import pickle

import numpy as np
import pytest

import pendula
from conftest import ctrl_c_latency

# A small grid: 11 x 7 cells of the double pendulum, 150 steps of 10 ms.
GRID = ["theta1=-3:3:11", "theta2=-pi:pi:7"]
CLI_GRID = ["--grid", GRID[0], "--grid", GRID[1]]
RUN = ["--dt", "0.01", "--steps", "150"]


def cli_sweep(cli, tmp_path, name, *extra):
    cli(["sweep", "double", *CLI_GRID, *RUN, *extra, "--out", name], tmp_path)
    return (tmp_path / name).read_bytes()


def test_the_cli_bytes_header_included(cli, tmp_path):
    want = cli_sweep(cli, tmp_path, "cli.npy", "--record", "final,flip-time,energy-error")
    r = pendula.sweep("double", GRID, dt=0.01, steps=150, record=("final", "flip-time", "energy-error"))
    assert r.data.shape == (7, 11, 6) and r.kernel.startswith("simd lanes")
    assert r.columns == ("theta1", "theta2", "omega1", "omega2", "flip_time", "energy_error")
    # The axes in the order given, the centres the CLI samples.
    (n1, c1), (n2, c2) = r.axes
    assert (n1, n2) == ("theta1", "theta2") and np.isclose(c2[0], -np.pi + np.pi / 7)
    assert r.save(tmp_path / "py.npy").read_bytes() == want
    # The dict form, and the CLI's comma-separated records, give the same sweep.
    d = pendula.sweep("double", {"theta1": (-3, 3, 11), "theta2": ("-pi", "pi", 7)}, dt=0.01, steps=150,
                      record="final,flip-time,energy-error")
    assert d.data.tobytes() == r.data.tobytes()
    assert d.description["fingerprint"] == r.description["fingerprint"]
    # The CLI's summary is the description.
    cli(["sweep", "double", *CLI_GRID, *RUN, "--record", "final,flip-time,energy-error", "--out", "s.npy",
         "--summary", "s.json"], tmp_path)
    summary = json.loads((tmp_path / "s.json").read_text())
    mine = r.description
    for key in ("pendula_sweep", "pendula", "system", "method", "dt", "steps", "axes", "columns", "shape", "shard",
                "shards", "offset", "count", "fingerprint", "data", "kernel"):
        assert mine[key] == summary[key], key
    back = pickle.loads(pickle.dumps(r))
    assert back.data.tobytes() == r.data.tobytes() and back.description == r.description
    assert "theta1" in r._repr_html_()


def test_the_scalar_path_is_the_clis_too_and_the_ensembles(cli, tmp_path):
    args = ["--method", "gauss-legendre-4", "--record", "final,flip-time"]
    cli(["sweep", "double", "--grid", "theta1=2:3:4", "--grid", "theta2=-1:1:3", "--dt", "0.01", "--steps", "40",
         *args, "--out", "gl.npy"], tmp_path)
    want = (tmp_path / "gl.npy").read_bytes()
    r = pendula.sweep("double", ["theta1=2:3:4", "theta2=-1:1:3"], method="gauss-legendre-4", dt=0.01, steps=40,
                      record=["final", "flip-time"], threads=2)
    assert r.kernel == "scalar, per cell"
    assert r.save(tmp_path / "py.npy").read_bytes() == want
    one = pendula.sweep("double", ["theta1=2:3:4", "theta2=-1:1:3"], method="gauss-legendre-4", dt=0.01,
                        steps=40, record=["final", "flip-time"], threads=1)
    assert one.data.tobytes() == r.data.tobytes()
    # pendula.ensemble runs the same cells on the scalar path: the same rows.
    (_, t1), (_, t2) = r.axes
    g1, g2 = np.meshgrid(t1, t2)
    y0s = np.stack([g1.ravel(), g2.ravel(), np.zeros(g1.size), np.zeros(g1.size)], axis=1)
    e = pendula.ensemble("double", y0s, method="gauss-legendre-4", dt=0.01, steps=40, threads=2,
                         record=("final", "flip-time"))
    assert e.kernel == "scalar"
    assert e.data.tobytes() == r.data.reshape(-1, 5).tobytes()


def test_threads_do_not_change_the_bits():
    kw = dict(dt=0.01, steps=300, until="flip", record=("final", "flip-time"))
    one = pendula.sweep("double", ["theta1=-3:3:40", "theta2=-3:3:30"], threads=1, **kw)
    two = pendula.sweep("double", ["theta1=-3:3:40", "theta2=-3:3:30"], threads=2, **kw)
    assert one.data.tobytes() == two.data.tobytes()
    flips = one.data[..., -1]
    assert np.isnan(flips).any() and (~np.isnan(flips)).any()


def test_shards_merge_either_way(cli, tmp_path):
    whole = cli_sweep(cli, tmp_path, "whole.npy")
    shards = [pendula.sweep("double", GRID, dt=0.01, steps=150, shard=(k, 3), threads=1 + k % 2) for k in (1, 2, 3)]
    assert [s.data.shape for s in shards] == [(25, 4), (26, 4), (26, 4)]
    merged = pendula.merge(reversed(shards))
    assert merged.save(tmp_path / "merged.npy").read_bytes() == whole
    # Python's shards, merged by the CLI.
    paths = [str(s.save(tmp_path / f"py{k}.npy")) for k, s in enumerate(shards, 1)]
    cli(["merge", *paths, "--out", "cli-merged.npy"], tmp_path)
    assert (tmp_path / "cli-merged.npy").read_bytes() == whole
    # A CLI shard, merged by Python with Python's.
    cli_sweep(cli, tmp_path, "cli2.npy", "--shard", "2/3")
    assert (tmp_path / "cli2.npy").read_bytes() == (tmp_path / "py2.npy").read_bytes()
    mixed = pendula.merge([shards[0], tmp_path / "cli2.npy", paths[2]])
    assert mixed.data.tobytes() == merged.data.tobytes() and mixed.data.shape == (7, 11, 4)


def test_merge_refuses_duplicate_missing_and_foreign_shards(cli, tmp_path):
    paths = []
    for k in (1, 2, 3):
        s = pendula.sweep("double", GRID, dt=0.01, steps=150, shard=f"{k}/3")
        paths.append(str(s.save(tmp_path / f"s{k}.npy")))
    with pytest.raises(pendula.InvalidValueError, match=r"s1\.npy and .*s1\.npy are both shard 1/3"):
        pendula.merge([paths[0], paths[0], paths[1], paths[2]])
    with pytest.raises(pendula.InvalidValueError, match="shard 2/3 is missing"):
        pendula.merge([paths[0], paths[2]])
    # Another step: another sweep, named.
    cli(["sweep", "double", *CLI_GRID, "--dt", "0.02", "--steps", "150", "--shard", "2/3", "--out", "other.npy"],
        tmp_path)
    with pytest.raises(pendula.InvalidValueError, match=r"other\.npy is a shard of another sweep than .*s1\.npy"):
        pendula.merge([paths[0], str(tmp_path / "other.npy"), paths[2]])
    # A truncated file is refused before it is believed.
    (tmp_path / "s3.npy").write_bytes((tmp_path / "s3.npy").read_bytes()[:-8])
    with pytest.raises(pendula.InvalidValueError, match=r"s3\.npy: .* truncated"):
        pendula.merge(paths)


def test_bad_input_names_the_value():
    with pytest.raises(pendula.InvalidValueError, match="hi of the theta1 axis"):
        pendula.sweep("double", ["theta1=1:0:4"], steps=10)
    with pytest.raises(pendula.InvalidValueError, match="`theta1`: set or swept"):
        pendula.sweep("double", ["theta1=0:1:4"], set={"theta1": 1}, steps=10)
    with pytest.raises(pendula.InvalidValueError, match="invalid record \"finale\" \\(did you mean `final`"):
        pendula.sweep("double", ["theta1=0:1:4"], record="finale", steps=10)
    with pytest.raises(pendula.InvalidValueError, match="invalid shard"):
        pendula.sweep("double", ["theta1=0:1:4"], shard=(4, 3), steps=10)
    with pytest.raises(pendula.InvalidValueError, match="`shards`"):
        pendula.sweep("double", ["theta1=0:1:4"], shard=(1, 5), steps=10)
    with pytest.raises(pendula.InvalidValueError, match="m1"):
        pendula.sweep("double", ["m1=-1:1:4"], steps=10)
    with pytest.raises(pendula.UnknownNameError, match="thetaa"):
        pendula.sweep("double", ["thetaa=0:1:4"], steps=10)
    with pytest.raises(pendula.UnsuitableMethodError, match="verlet"):
        pendula.sweep("double", ["theta1=0:1:4"], set={"damping": 0.1}, method="verlet", steps=10)
    with pytest.raises(pendula.UnsuitableMethodError, match="dopri5 needs adaptive steps"):
        pendula.sweep("double", ["theta1=0:1:4"], method="dopri5", steps=10)
    with pytest.raises(pendula.InvalidValueError, match="t_end"):
        pendula.sweep("double", ["theta1=0:1:4"], dt=0.3, t_end=1)


@pytest.mark.parametrize("method", ["gauss-legendre-4", "tao-4"])
def test_ctrl_c_interrupts_a_long_sweep_quickly(method):
    # Minutes of work on the scalar path and on Tao's lanes (which look at the flag before
    # each lane group); SIGINT after 0.3 s must end it within 0.2 s.
    latency = ctrl_c_latency(
        lambda: pendula.sweep("double", ["theta1=-3:3:2000", "theta2=-3:3:500"], method=method, dt=0.001, steps=5_000),
        after=0.3,
    )
    assert latency < 0.2, latency
