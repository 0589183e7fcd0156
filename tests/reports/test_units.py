"""The identification figures draw NRMSE in per cent, as every table of the report gives
it, and say their units (mfflap.reports.identification)."""

from types import SimpleNamespace

import numpy as np

from mfflap.reports.identification import applicability_figure, strategy_error_figure


def _result(nrmse: np.ndarray):
    """An identification result of six cases at two frequencies and heave amplitudes."""
    f = np.array([0.5, 0.5, 1.0, 1.0, 2.0, 2.0])
    h = np.array([0.1, 0.3, 0.1, 0.3, 0.1, 0.3])
    params = [{"frequency": fv, "heave_amplitude": hv} for fv, hv in zip(f, h, strict=True)]
    return SimpleNamespace(metrics={"normal_force": {"nrmse": nrmse}}, case_parameters=params,
                           cases=[f"c{i}" for i in range(6)])


def test_the_identification_figures_draw_nrmse_in_per_cent(monkeypatch):
    import mfflap.reports.identification as identification

    nrmse = np.array([0.05, 0.08, 0.12, 0.2, 0.3, 0.04])
    result = _result(nrmse)
    monkeypatch.setattr(identification, "_param",
                        lambda res, key: np.array([p[key] for p in res.case_parameters]))
    monkeypatch.setattr(identification, "heave_strouhal",
                        lambda res, velocity: np.linspace(0.1, 1.0, 6))
    fig = applicability_figure(result, 0.3)
    points = fig.axes[0].collections[0].get_offsets()[:, 1]
    assert np.allclose(points, 100 * nrmse)
    assert fig.axes[0].get_ylabel().endswith("[%]")
    curves = strategy_error_figure({"uniform": result})
    ax = curves.axes[0]
    assert ax.get_ylabel().endswith("[%]")
    means = ax.lines[0].get_ydata()
    assert np.allclose(means, 100 * np.array([0.065, 0.16, 0.17]))


def test_the_report_shows_each_weightings_weight_per_frequency():
    from mfflap.identification.weights import frequency_weights
    from mfflap.reports.identification import weights_table_html

    frequencies = [0.1, 0.2, 0.5, 1.0, 2.0]
    results = {name: SimpleNamespace(weights=frequency_weights(frequencies, name))
               for name in ("uniform", "low", "high")}
    html = weights_table_html(results)
    assert html.count("<tr>") == 4 and "f = 0.1 Hz" in html and "f = 2 Hz" in html
    assert "0.4" in html and "0.05" in html and "0.2" in html  # low, high and uniform's
