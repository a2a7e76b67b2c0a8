"""The calibration report: one self-contained HTML page beside ``calibration.yaml``.

It is rendered from the calibration folder alone (read through
:func:`posegen.calibrate.read_calibration`), so it can be rebuilt at any time and the
calibrate stage never depends on the viewer: ``posegen calibrate`` writes the folder,
then calls :func:`write_report`. Sections: summary, held-out and training figures,
residual plots, cross-validation, identified parameters with their posterior std,
conditioning and correlation of the base regressor, outliers and rejected rows, and the
3D overlay of the nominal and calibrated robot (the viewer's page, inlined).
"""

from __future__ import annotations

import concurrent.futures
import html
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from posegen.calibrate import COMPONENTS, ContactSet
from posegen.errors import InputError
from posegen.io import OutputKind, claim_output, write_atomic
from posegen.parallel import Backend
from posegen.view.artefact import CalibrationArtefact, open_artefact
from posegen.view.calibration_view import displayed
from posegen.view.report_figures import ReportFigure, figure_uris, strongest_correlations
from posegen.view.viewer import Page, html_page

REPORT_FILE = "report.html"
STYLE = """
body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
h1{margin-bottom:0.2em} h2{margin-top:1.6em;border-bottom:1px solid #ddd}
table{border-collapse:collapse;font-size:0.85em;margin:0.5em 0}
td,th{border:1px solid #ddd;padding:0.2em 0.5em;text-align:right} th{background:#f4f4f4}
td.name,th.name{text-align:left} .muted{color:#777} img{max-width:100%}
iframe{width:100%;height:560px;border:1px solid #ccc}
.scroll{max-height:28em;overflow-y:auto;display:inline-block} .warning{color:#b00;font-weight:bold}
"""


def _e(value: object) -> str:
    return html.escape(str(value))


def table(header: Sequence[str], rows: Iterable[Sequence[object]], names: int = 1) -> str:
    """An HTML table; the first ``names`` columns are left-aligned text."""
    head = "".join(f'<th class="name">{_e(h)}</th>' if i < names else f"<th>{_e(h)}</th>" for i, h in enumerate(header))
    body = "".join(
        "<tr>"
        + "".join(f'<td class="name">{_e(v)}</td>' if i < names else f"<td>{_e(v)}</td>" for i, v in enumerate(row))
        + "</tr>"
        for row in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def _summary(report: dict[str, Any], artefact: CalibrationArtefact) -> str:
    counts = {s: sum(c.set == s for c in artefact.record.contacts) for s in ContactSet}
    prov = report.get("provenance") or {}
    model = report.get("model") or {}
    noise = (report.get("noise") or {}).get("contact") or {}
    base = report.get("base_parameters") or {}
    rows = [
        ("chains", ", ".join(report.get("chains") or [])),
        ("table sessions", ", ".join(report.get("sessions") or [])),
        ("contacts: training / left out / held-out", " / ".join(str(counts[s]) for s in ContactSet)),
        (
            "interpretable model (one-standard-error rule; not a file)",
            f"{model.get('candidate')}, prior x{model.get('prior_scale')}",
        ),
        *(
            (f"its predicted held-out error, {chain} (grouped CV)", _components(error.get("mean_abs") or {}))
            for chain, error in (model.get("predicted_error") or {}).items()
        ),
        (
            "base parameters, contacts (and floor equations), of all",
            f"{base.get('contacts')} ({base.get('contacts_and_floor')}) of {base.get('parameters')}",
        ),
        (
            "contact noise (estimated)",
            f"{noise.get('z_mm')} mm, {noise.get('roll_deg')} deg, {noise.get('pitch_deg')} deg",
        ),
        ("robot model sha256", str(prov.get("robot_model_sha256", ""))[:16] + "..."),
        ("posegen", prov.get("posegen_version", "")),
    ]
    warnings = "".join(f'<p class="warning">{_e(w)}</p>' for w in report.get("warnings") or [])
    return table(("", "value"), rows, names=2) + warnings


FILES = (("urdf", "calibrated.urdf"), ("compensated", "with_compliance/"), ("nominal_urdf", "nominal URDF"))


def _deliverables(report: dict[str, Any]) -> str:
    """What to load for which stack: each file's model, its predicted error and its error as a stack sees it."""
    section = report.get("deliverables") or {}
    rows = []
    for key, _ in FILES:
        entry = section.get(key)
        if not isinstance(entry, dict):
            continue
        files = ", ".join(entry.get("files") or ["the URDF as it is (not written)"])
        model = f"{entry.get('candidate', 'nominal URDF')}, prior x{entry.get('prior_scale', '-')}"
        head = (files, entry.get("load_with", "for comparison"), model)
        for chain, error in (entry.get("predicted_error") or {}).items():
            rows.append((*head, f"{chain}: predicted held-out (grouped CV)", _components(error.get("mean_abs") or {})))
        for chain, error in (entry.get("held_out") or {}).items():
            if chain != "all":
                label = f"{chain}: held-out, {error.get('contacts')} contacts"
                rows.append((*head, label, _components(error.get("mean_abs") or {})))
    note = f'<p class="muted">{_e(section.get("rule", ""))}. Judged {_e(section.get("judged", ""))}.</p>'
    return table(("files", "load with", "model", "error", "height / roll / pitch"), rows, names=4) + note


def _components(values: dict[str, Any]) -> str:
    shown = (values.get(c, "") for c in COMPONENTS)
    return " / ".join("-" if v is None else f"{v:.2f}" if isinstance(v, float) else f"{v}" for v in shown) + (
        " (mm / deg / deg)"
    )


def _number(value: float | None) -> str:
    """Three decimals; "-" for a component nothing measured (roll and pitch of point contacts)."""
    return "-" if value is None else f"{value:.3f}"


def _residual_tables(report: dict[str, Any]) -> str:
    """Every file's errors as a stack loading it sees them, per set and chain (and the interpretable model's)."""
    section = report.get("deliverables") or {}
    entries = [(name, section.get(key)) for key, name in FILES]
    entries.append(("interpretable model (not a file)", report.get("model")))
    rows = []
    for label, key in (("training", "training"), ("held-out", "held_out")):
        for name, entry in entries:
            for chain, result in ((entry or {}).get(key) or {}).items() if isinstance(entry, dict) else ():
                mean, rms = result["mean_abs"], result["rms"]
                shown = (f"{_number(mean[c])} / {_number(rms[c])}" for c in COMPONENTS)
                rows.append((label, chain, name, result.get("contacts", ""), *shown))
    header = ("set", "chain", "file", "contacts", "height (mm)", "roll (deg)", "pitch (deg)")
    return table(header, rows, names=3) + '<p class="muted">mean absolute / RMS</p>'


def _cross_validation(report: dict[str, Any]) -> str:
    selection = report.get("model_selection") or {}
    rows = [
        (
            r.get("candidate"),
            r.get("prior_scale"),
            r.get("free_parameters"),
            f"{r.get('score')} +- {r.get('se')}",
            *(_components(e) for e in (r.get("chains") or {}).values()),
        )
        for r in selection.get("ranking") or []
    ]
    if not rows:
        return "<p>No cross-validation in this report.</p>"
    chains = list(((selection.get("ranking") or [{}])[0].get("chains") or {}).keys())
    header = ("candidate", "prior scale", "free parameters", "score +- SE", *(f"{c}: predicted error" for c in chains))
    chosen = selection.get("chosen") or {}
    stability = (selection.get("stability") or {}).get("share_of_seeds")
    return (
        f"<p>Rule: {_e(selection.get('rule', ''))}. Chosen: <b>{_e(chosen.get('candidate'))} x"
        f"{_e(chosen.get('prior_scale'))}</b>, the same pick on {stability} of the fold seeds.</p>"
        + table(header, rows, names=1)
    )


def _parameters(report: dict[str, Any]) -> str:
    rows = []
    for p in report.get("parameters") or []:
        deviation, std, unit = displayed(p)
        ratio = abs(deviation) / std if std > 0 else float("inf")
        rows.append((p["name"], p.get("kind", ""), unit, f"{deviation:+.4f}", f"{std:.4f}", f"{ratio:.1f}"))
    header = ("parameter", "kind", "unit", "deviation from URDF", "posterior std", "|deviation| / std")
    return f'<div class="scroll">{table(header, rows, names=2)}</div>'


def _conditioning(artefact: CalibrationArtefact, figures: dict[ReportFigure, str]) -> str:
    posterior = artefact.record.posterior
    pairs = table(
        ("parameter", "parameter", "correlation"),
        ((a, b, f"{rho:+.3f}") for a, b, rho in strongest_correlations(posterior)),
        names=2,
    )
    return (
        f"<p>Condition number of the noise-whitened regressor: <b>{posterior.condition:.4g}</b> "
        f"(with the prior: {posterior.condition_with_prior:.4g}).</p>"
        f'<img src="{figures[ReportFigure.SINGULAR_VALUES]}" alt="singular values">'
        f"<h3>Most correlated pairs</h3>{pairs}"
        f'<img src="{figures[ReportFigure.CORRELATION]}" alt="correlation matrix">'
    )


def _outliers(report: dict[str, Any]) -> str:
    left_out = report.get("left_out") or []
    rejected = report.get("rejected_rows") or []
    parts = []
    if left_out:
        rows = ((f"{r.get('file')}:{r.get('line')}", r.get("spot"), r.get("reason"), r.get("value")) for r in left_out)
        parts.append(table(("row", "spot", "reason", "residual or offset"), rows))
    else:
        parts.append("<p>No training row was left out.</p>")
    if rejected:
        parts.append("<h3>Input rows left out as unusable</h3><ul>")
        parts.extend(f"<li>{_e(r)}</li>" for r in rejected)
        parts.append("</ul>")
    return "".join(parts)


def _figures_and_view(artefact: CalibrationArtefact, backend: Backend | None) -> tuple[dict[ReportFigure, str], Page]:
    """The report's figures and its 3D page: the figures on ``backend``'s workers while the page is made here."""
    record = artefact.record
    if backend is None or backend.slots < 2:
        return figure_uris(record.contacts, record.posterior), html_page(artefact)
    with concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="posegen-report-figures") as waiting:
        figures = waiting.submit(figure_uris, record.contacts, record.posterior, backend)
        view = html_page(artefact)
        return figures.result(), view


def report_html(artefact: CalibrationArtefact, shown_as: Path | None = None, backend: Backend | None = None) -> str:
    """The report page of a calibration folder (its figures drawn on ``backend``'s workers, if any)."""
    report = artefact.record.report
    figures, page = _figures_and_view(artefact, backend)
    view = page.html
    sections = [
        ("What to load: the files written", _deliverables(report)),
        ("Summary", _summary(report, artefact)),
        ("Every file's errors, as a stack loading it sees them", _residual_tables(report)),
        (
            "Every contact",
            f'<img src="{figures[ReportFigure.RESIDUALS]}" alt="residuals per contact">'
            f'<img src="{figures[ReportFigure.DISTRIBUTION]}" alt="residual distributions">',
        ),
        ("Model selection: repeated grouped cross-validation", _cross_validation(report)),
        ("The interpretable model's parameters", _parameters(report)),
        ("Conditioning and correlation of the regressor", _conditioning(artefact, figures)),
        ("Rows left out", _outliers(report)),
        (
            "3D: nominal (grey) and calibrated (blue) robot at each contact",
            "<p>Arrows: height residual at each contact, 20x magnified; grey under the nominal URDF, under "
            "calibrated.urdf coloured by "
            "noise sigmas (green within 1, amber within 3, red beyond). The playback time is the contact "
            "number.</p>"
            f'<iframe title="3D view" srcdoc="{html.escape(view, quote=True)}"></iframe>',
        ),
    ]
    body = "".join(f"<h2>{_e(title)}</h2>{content}" for title, content in sections)
    where = artefact.path if shown_as is None else shown_as  # a staging folder shows its destination
    title = f"posegen calibration report: {where}"
    return (
        f'<!doctype html><html lang="en"><head><meta charset="utf-8"><title>{_e(title)}</title>'
        f"<style>{STYLE}</style></head><body><h1>Calibration report</h1>"
        f'<p class="muted">{_e(where.resolve())}</p>{body}</body></html>'
    )


def write_report(directory: str | Path, config_path: str | None = None) -> Path:
    """Write ``report.html`` into a calibration folder (atomically) and return its path.

    Raises:
        PosegenError: The folder is not a complete calibration folder.

    """
    if not Path(directory).is_dir():
        raise InputError(f"{directory}: not a calibration folder")
    with claim_output(directory, OutputKind.FOLDER):
        return write_report_into(directory, config_path)


def write_report_into(
    directory: str | Path,
    config_path: str | None = None,
    shown_as: str | Path | None = None,
    backend: Backend | None = None,
) -> Path:
    """Write ``report.html`` into a calibration folder the caller holds, and return its path.

    For a folder being made (``posegen calibrate`` writes the report into its staging
    folder, before the folder is swapped in, so the report and the calibration come from
    one run).

    Args:
        directory: The calibration folder (complete but for the report).
        config_path: Scene config to use instead of the one saved in the calibration.
        shown_as: The folder's name to show in the page (its destination); default ``directory``.
        backend: Where the figures are drawn (meanwhile this process makes the 3D page);
            None: here. The same page either way.

    Raises:
        PosegenError: The folder is not a complete calibration folder.

    """
    artefact = open_artefact(directory, config_path)
    if not isinstance(artefact, CalibrationArtefact):
        raise InputError(f"{directory}: not a calibration folder")
    path = artefact.record.directory / REPORT_FILE
    write_atomic(path, report_html(artefact, None if shown_as is None else Path(shown_as), backend))
    return path
