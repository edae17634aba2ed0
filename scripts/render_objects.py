"""Render every catalog object to a PNG, and all of them to one contact sheet.

Usage::

    python scripts/render_objects.py                 # all objects into docs/objects/
    python scripts/render_objects.py --objects cat fish --out /tmp/renders

Each object is decimated, back-face culled and flat-shaded (Lambert plus ambient) in
an orthographic matplotlib 3D view (:mod:`tactile_sim.objects.render`). Objects are
built first if they are not cached.
"""

from __future__ import annotations

import sys
from pathlib import Path

from tactile_sim.cli import ArgumentParser, integer, require_writable, run_cli
from tactile_sim.objects.render import RenderConfig, render_objects


def run(config: RenderConfig) -> list[Path]:
    """Render the configured objects; print and return the written PNG paths."""
    written = render_objects(config)
    for path in written:
        print(path)
    return written


def parse_args(argv: list[str] | None = None) -> RenderConfig:
    """What to render from the command line (``argv``: default ``sys.argv``); a bad option
    or an output directory that cannot be written exits 2 here."""
    parser = ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--objects", nargs="*", default=[], help="object names (default: all)")
    parser.add_argument("--out", type=Path, default=RenderConfig.out_dir, help="output directory")
    parser.add_argument(
        "--faces", type=integer(100), default=RenderConfig.faces, help="faces drawn (>= 100)"
    )
    parser.add_argument("--no-contact-sheet", action="store_true", help="skip the contact sheet")
    args = parser.parse_args(argv)
    require_writable(parser, "--out", args.out, directory=True)
    return RenderConfig(
        objects=tuple(args.objects),
        out_dir=args.out,
        faces=args.faces,
        contact_sheet=not args.no_contact_sheet,
    )


def main(argv: list[str] | None = None) -> int:
    """Parse the arguments and render; 2 on an unknown object or a failed build, 130 on
    Ctrl-C."""
    config = parse_args(argv)
    return run_cli(lambda: run(config), name="render_objects")


if __name__ == "__main__":
    sys.exit(main())
