"""Write twelve meshes like users bring: six scans (holes, loose pieces, one low-poly) and
six CAD-like parts (a bracket, a gear, four blocks with bosses and bores).

python scripts/user_meshes.py my_meshes --units mm
python scripts/benchmark.py --mesh-dir my_meshes --units mm --with-catalog --method fast
"""

from __future__ import annotations

import sys
from pathlib import Path

from recognition.surfaces.mesh_files import UNITS
from tactile_sim.cli import ArgumentParser, integer, require_writable, run_cli
from tactile_sim.objects.user_meshes import write_user_meshes


def main(argv: list[str] | None = None) -> int:
    """Parse the arguments and write the meshes; 2 on bad input."""
    p = ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("out", type=Path, help="folder to write (PLY, OBJ, STL, OFF and GLB files)")
    p.add_argument("--units", choices=tuple(UNITS), default="mm", help="of the files")
    p.add_argument("--seed", type=integer(0), default=0)
    a = p.parse_args(argv)
    require_writable(p, "out", a.out, directory=True)

    def write() -> None:
        for path in write_user_meshes(a.out, a.seed, a.units):
            print(path)

    return run_cli(write)


if __name__ == "__main__":
    sys.exit(main())
