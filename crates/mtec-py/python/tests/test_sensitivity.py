"""mtec.sensitivity: the dict `mtec sensitivity --json` prints, intervals included."""

import pytest

import mtec


def test_function_matches_the_cli_with_intervals(cli):
    for method in ("efast", "sobol", "morris"):
        # the bootstrap count is Sobol's and Morris's (EFAST refuses it: it repeats its phases)
        boot = {} if method == "efast" else {"num_resamples": 50}
        got = mtec.sensitivity(function="ishigami", method=method, samples=600, seed=4,
                               conf_level=0.9, **boot)
        want = cli.json("sensitivity", "--function", "ishigami", "--method", method,
                        "--samples", 600, "--seed", 4, "--conf-level", 0.9,
                        *[a for k, v in boot.items() for a in ("--num-resamples", v)], "--json")
        assert got.keys() == want.keys()
        assert got["conf_level"] == 0.9
        conf = ["mu_star_conf"] if method == "morris" else ["S1_conf", "ST_conf"]
        for k in conf + (["mu_star"] if method == "morris" else ["S1", "ST"]):
            assert got[k] == pytest.approx(want[k], rel=1e-12, abs=1e-15), k
        assert all(c >= 0.0 for k in conf for c in got[k])


def test_machine_at_one_pose(tmp_path, cli):
    (tmp_path / "m.toml").write_text(
        'chain = "WXYFZT"\ntool_offset_mm = [0, 0, 100]\n[axes.X]\ntravel = [0, 600]\n'
        '[axes.Y]\ntravel = [0, 800]\n[axes.Z]\ntravel = [0, 300]\n')
    (tmp_path / "s.csv").write_text(
        "element,mean,std,unit\nEXX,1,2,um\nEYY,0,3,um\nECX,0,5,urad\n")
    got = mtec.sensitivity(machine=tmp_path / "m.toml", stats=tmp_path / "s.csv",
                           at=[300.0, 400.0, 150.0], samples=300)
    want = cli.json("sensitivity", "--machine", tmp_path / "m.toml", "--stats",
                    tmp_path / "s.csv", "--at", "300,400,150", "--samples", 300, "--json")
    assert got["evaluations"] == want["evaluations"] == 3 * 300 * 10
    # Ex, Ey, |E| vary and have intervals; Ez does not vary (no element reaches it): no interval
    assert [("S1_conf" in o) for o in got["outputs"]] == [True, True, False, True]
    for g, w in zip(got["outputs"], want["outputs"]):
        assert g.keys() == w.keys()
        for k in ("S1", "ST", "S1_conf", "ST_conf"):
            if k in w:
                assert g[k] == pytest.approx(w[k], rel=1e-12, abs=1e-15), (g["output"], k)


def test_bad_input_raises_located_error(tmp_path):
    (tmp_path / "m.toml").write_text(
        'chain = "WXYFZT"\n[axes.X]\ntravel = [0, 600]\n[axes.Y]\ntravel = [0, 800]\n'
        '[axes.Z]\ntravel = [0, 300]\n')
    (tmp_path / "s.csv").write_text("element,mean,std,unit\nEXX,1,2,urad\n")
    with pytest.raises(mtec.InputError) as e:
        mtec.sensitivity(machine=tmp_path / "m.toml", stats=tmp_path / "s.csv", at=[1, 2, 3])
    assert e.value.line == 2 and e.value.column == 4
    with pytest.raises(ValueError):
        mtec.sensitivity(function="ishigami", method="fast")
    with pytest.raises(ValueError):
        mtec.sensitivity(function="ishigami", conf_level=1.5)
