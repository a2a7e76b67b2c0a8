"""``posegen view``: the 3D view of a pool, selection, route or calibration folder."""

from __future__ import annotations

import argparse

from posegen.cli.options import port

# the viewer's defaults (posegen.view.DEFAULT_PORT, DEFAULT_HOST), spelled here so that the command
# line does not import the viewer (viser, trimesh: ~1 s) for the commands that do not need it
DEFAULT_PORT_HELP = 8080
DEFAULT_HOST_HELP = "127.0.0.1"

NAME = "view"
HELP = "3D view of a pool, selection, route or calibration folder (live, or one HTML file)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("artefact", help="pool, selection or route file, or calibration folder")
    parser.add_argument("--html", default=None, help="write one self-contained HTML page here instead of serving")
    parser.add_argument("--port", type=port, default=None, help=f"live viewer port (default {DEFAULT_PORT_HELP})")
    parser.add_argument(
        "--host", default=None, help=f"live viewer address (default {DEFAULT_HOST_HELP}: this machine only)"
    )
    parser.add_argument("--config", default=None, help="scene config (default: the one saved in the artefact)")


def run(args: argparse.Namespace) -> int:
    """Write the page, or serve the live viewer until Ctrl-C (which ends it normally)."""
    from posegen.view import DEFAULT_HOST, DEFAULT_PORT, open_artefact, serve, write_html_file

    if args.html is not None:  # "" names no file: refused, not served
        page = write_html_file(args.artefact, args.html, args.config)
        print(
            f"view: {page.steps} steps, {page.duration_s:.1f} s of playback -> {args.html} "
            f"({page.size_bytes / 1e6:.2f} MB, built in {page.build_s + page.serialize_s:.1f} s; opens offline)"
        )
        return 0
    artefact = open_artefact(args.artefact, args.config)

    def ready(url: str) -> None:
        print(f"view: {args.artefact} at {url} (Ctrl-C to stop)", flush=True)

    try:
        host = DEFAULT_HOST if args.host is None else args.host
        serve(artefact, host, DEFAULT_PORT if args.port is None else args.port, ready=ready)
    except KeyboardInterrupt:
        print("view: stopped")
    return 0
