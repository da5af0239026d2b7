"""Figures for people (issue 54 item 10): what `mfm simulate`'s and `mfm plot`'s figure draws, not
its pixels: the panels and their units, the wave elevation, the PTO power in kW with its mean at
the mean, the wave's PSD against the elevation's variance and the sea's target spectrum, many
coordinates in grouped panels whose legends sit beside the curves, and the summary's total power
of many PTOs. Smoke runs (RM3 in a JONSWAP sea, Wu & Yuan's 18 coordinates without water, a
double pendulum with two dampers); figures written under out/tests/.
"""
from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import hydro  # noqa: E402
import mfm  # noqa: E402
from mfm.io import plotting  # noqa: E402

from conftest import CONFIGS, ROOT  # noqa: E402

OUT = ROOT / "out" / "tests" / "plotting"
SEA = hydro.Jonswap(hs=2.0, tp=9.0, seed=1)


@pytest.fixture(scope="module")
def rm3_irregular():
    OUT.mkdir(parents=True, exist_ok=True)
    model = mfm.load(CONFIGS / "rm3.toml")
    # 600 s: the second half holds ~33 peak periods, enough segments for Welch's estimate
    return mfm.simulate(model, SEA, duration=600.0, dt=0.1, ramp=20.0)


def _by_ylabel(fig):
    return {a.get_ylabel(): a for a in fig.axes}


def _line(a, prefix):
    lines = [ln for ln in a.get_lines() if ln.get_label().startswith(prefix)]
    assert len(lines) == 1, [ln.get_label() for ln in a.get_lines()]
    return lines[0]


def _legends_beside(fig):
    """Every legend lies to the right of its axes (in the figure's pixels, once drawn)."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    for a in fig.axes:
        leg = a.get_legend()
        if leg is not None:
            assert leg.get_window_extent(r).x0 >= a.get_window_extent(r).x1 - 1e-6, a.get_ylabel()


def test_an_irregular_run_s_figure(rm3_irregular):
    ds = rm3_irregular
    fig = plotting.plot_simulation(ds, sea=SEA)
    fig.savefig(OUT / "rm3_jonswap.png", dpi=60)
    ax = _by_ylabel(fig)
    # η, q in m and in rad, the PTO power, the wave's PSD and the coordinates' PSDs per unit
    assert [a.get_ylabel() for a in fig.axes] == [
        "η [m]", "q [m]", "q [rad]", "PTO power [kW]", "S_η [m² s/rad]", "PSD of q [m² s/rad]",
        "PSD of q [rad² s/rad]"]
    assert ax["PTO power [kW]"].get_xlabel() == "time [s]"
    assert all(ax[k].get_xlabel() == "ω [rad/s]" for k in list(ax)[4:])
    np.testing.assert_array_equal(_line(ax["η [m]"], "η").get_ydata(), ds.eta.values)

    # the power in kW, its mean over the second half (the summary's window) drawn across it
    a = ax["PTO power [kW]"]
    np.testing.assert_allclose(_line(a, "float.stroke").get_ydata(),
                               ds.pto_power.sel(pto="float.stroke").values / 1e3, rtol=0, atol=0)
    h0 = ds.sizes["time"] // 2
    mean_kw = float(ds.pto_power.isel(time=slice(h0, None)).mean()) / 1e3
    m = _line(a, "mean")
    np.testing.assert_allclose(m.get_ydata(), [mean_kw, mean_kw], rtol=1e-12)
    np.testing.assert_array_equal(m.get_xdata(), [float(ds.time[h0]), float(ds.time[-1])])
    assert f"{mean_kw:.4g} kW" in m.get_label()

    # the PSD's area is the elevation's variance: Welch's segments are Hann-windowed, so its
    # integral is the mean of the segments' windowed variances; the two differ by the estimate's
    # own scatter, of relative size 1/sqrt(K) for K segments (the standard error of one bin of a
    # Welch PSD; the area, summing many bins, scatters less). Measured: -7.0e-2 with K = 10.
    a = ax["S_η [m² s/rad]"]
    w = _line(a, "η, Welch")
    K = int(w.get_label().split("(")[1].split()[0])
    assert K >= 8
    eta = ds.eta.values[h0:]
    area = np.trapezoid(w.get_ydata(), w.get_xdata())
    assert area == pytest.approx(np.var(eta), rel=1.0 / math.sqrt(K))
    # a variance read with S's 2π wrong (per Hz, not per rad/s) lies far outside that
    assert abs(2 * np.pi * area / np.var(eta) - 1.0) > 1.0 / math.sqrt(K)
    target = _line(a, "target")
    np.testing.assert_allclose(target.get_ydata(), SEA.spectrum(target.get_xdata()), rtol=1e-15)
    assert a.get_xlim() == pytest.approx(SEA.band)
    _legends_beside(fig)
    plt.close(fig)


def test_the_figure_of_a_file_rebuilds_its_sea(rm3_irregular, tmp_path):
    # `mfm plot run.nc` has no sea object: the attribute's repr gives the same target spectrum
    sea = plotting.sea_of(rm3_irregular)
    assert repr(sea) == repr(SEA)
    assert plotting.sea_of(rm3_irregular.assign_attrs(sea="UserSpectrum(omega=array([...]))")) is None
    path = OUT / "rm3_jonswap_file.png"
    assert "wave elevation" in plotting.save_result_plot(rm3_irregular, path, dpi=50)
    assert path.stat().st_size > 0


def test_many_coordinates_share_grouped_panels(tmp_path):
    # Wu & Yuan's 18 coordinates (platform 6, twelve hinges): without water, a second of the
    # mechanics and its PTO dampers (the layout of the figure, not the physics, is under test)
    OUT.mkdir(parents=True, exist_ok=True)
    model = mfm.load(CONFIGS / "wu_yuan_m1_td.toml", hydro=False)
    q0 = {f"wec{i}.angle": 0.05 * (-1) ** i for i in range(1, 13)}
    ds = mfm.simulate(model, None, duration=1.0, dt=0.01, q0=q0)
    fig = plotting.plot_simulation(ds)
    fig.savefig(OUT / "wu_yuan_mechanics.png", dpi=50)
    titles = [(a.get_ylabel(), a.get_title(loc="left")) for a in fig.axes]
    q = [t for t in titles if t[0].startswith("q [")]
    assert q == [("q [m]", ""), ("q [rad]", "platform"), ("q [rad]", "wec1 … wec6"),
                 ("q [rad]", "wec7 … wec12")]
    spectra = [t[1].split(", t ≥")[0] for t in titles if t[0].startswith("amplitude of q")]
    assert spectra == ["amplitude spectrum of the coordinates" + g for g in
                       ("", " (platform)", " (wec1 … wec6)", " (wec7 … wec12)")]
    power = [t for t in titles if t[0] == "PTO power [kW]"]
    assert power == [("PTO power [kW]", "total of 12 PTOs"),
                     ("PTO power [kW]", "wec1.angle … wec6.angle"),
                     ("PTO power [kW]", "wec7.angle … wec12.angle")]
    for a in fig.axes:
        assert len(a.get_lines()) <= plotting.MAX_LINES + 1, a.get_ylabel()   # + a mean line
    a = next(a for a in fig.axes if a.get_title(loc="left") == "total of 12 PTOs")
    np.testing.assert_allclose(_line(a, "total").get_ydata(),
                               ds.pto_power.sum("pto").values / 1e3, rtol=1e-12)
    _line(a, "mean")
    assert not [a for a in fig.axes if a.get_ylabel() == "η [m]"]        # still water: no η
    _legends_beside(fig)
    plt.close(fig)


def test_coordinate_panels_keep_a_small_model_by_unit():
    names = ["spar.surge", "spar.heave", "spar.pitch", "float.stroke"]
    assert plotting.coordinate_panels(names, ["m", "m", "rad", "m"]) == [
        ("m", [0, 1, 3], ""), ("rad", [2], "")]
    seven = [f"f{i}.angle" for i in range(7)]
    assert [p[1] for p in plotting.coordinate_panels(seven, ["rad"] * 7)] == [[0, 1, 2, 3],
                                                                                [4, 5, 6]]


def test_the_summary_gives_the_total_of_many_ptos(tmp_path, capsys):
    # the double pendulum with a damper on each hinge: two PTOs
    from mfm_cli import main

    text = (CONFIGS / "double_pendulum.toml").read_text()
    cfg = tmp_path / "two_dampers.toml"
    cfg.write_text(text.replace("point = [0.0, 0.0, 0.0]\n", "point = [0.0, 0.0, 0.0]\ndamping = 0.1\n"))
    out = tmp_path / "run.nc"
    main(["simulate", str(cfg), "--initial", "upper.angle=1.0", "--duration", "4", "--dt",
          "0.005", "--progress", "off", "--out", str(out)])
    text = capsys.readouterr().out
    each = [float(line.split(":")[1].split()[0]) for line in text.splitlines()
            if line.strip().startswith("mean power of") and "all" not in line]
    total = [line for line in text.splitlines() if "mean power of all 2 PTOs" in line]
    assert len(each) == 2 and len(total) == 1, text
    assert float(total[0].split(":")[1].split()[0]) == pytest.approx(sum(each), rel=1e-5)
    assert out.with_suffix(".png").exists()


def test_the_notebooks_time_series_give_power_in_kw_with_its_mean(rm3_irregular):
    # quickstart's plot_time_series(ds, ["eta", "q", "pto_power"])
    ds = rm3_irregular
    fig = plotting.plot_time_series(ds, ["eta", "q", "pto_power"])
    fig.savefig(OUT / "rm3_time_series.png", dpi=50)
    ax = _by_ylabel(fig)
    assert list(ax) == ["eta [m]", "q [m or rad (per coordinate: coordinate_unit)]",
                        "pto_power [kW]"]
    a = ax["pto_power [kW]"]
    np.testing.assert_allclose(_line(a, "float.stroke").get_ydata(),
                               ds.pto_power.sel(pto="float.stroke").values / 1e3, rtol=1e-15)
    h0 = ds.sizes["time"] // 2
    mean_kw = float(ds.pto_power.isel(time=slice(h0, None)).mean()) / 1e3
    np.testing.assert_allclose(_line(a, "mean").get_ydata(), [mean_kw, mean_kw], rtol=1e-12)
    _legends_beside(fig)
    plt.close(fig)


def test_a_regular_wave_s_spectra_mark_the_wave(rm3_irregular):
    # the drawing given a regular sea (the series are the irregular run's: what is drawn is
    # under test): amplitude spectra over 0 to 4 ω (the wave and its harmonics), the wave marked
    sea = hydro.Regular(height=2.0, period=8.0)
    fig = plotting.plot_simulation(rm3_irregular, sea=sea)
    spectra = [a for a in fig.axes if a.get_xlabel() == "ω [rad/s]"]
    assert [a.get_ylabel() for a in spectra] == ["amplitude of q [m]", "amplitude of q [rad]"]
    for a in spectra:
        assert a.get_xlim() == pytest.approx((0.0, 4 * sea.omega))
        np.testing.assert_allclose(_line(a, "the wave").get_xdata(), [sea.omega] * 2)
    assert not [a for a in fig.axes if a.get_ylabel().startswith("S_η")]   # no PSD, no target
    plt.close(fig)
