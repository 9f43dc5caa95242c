"""Refresh the replay tier's references, with a diff report of what changed.

.venv/bin/python tests/replay/refresh.py            # report only (exit 1 if anything moved)
.venv/bin/python tests/replay/refresh.py --write    # report, then store the new outputs
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from replay_harness import RECORDINGS, compare, outputs, reference_path

from dronewrapper.runtime.arguments import CommandParser, first_line


def main() -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("names", nargs="*", help=f"recordings (default: {', '.join(RECORDINGS)})")
    parser.add_argument("--write", action="store_true", help="store the new references")
    args = parser.parse_args()
    changed = False
    for name in args.names or list(RECORDINGS):
        got = outputs(name)
        path = reference_path(name)
        if path.exists():
            diff = compare(got, json.loads(path.read_text()))
            print(diff.report(name))
            changed |= bool(diff.problems)
        else:
            print(f"{name}: no reference yet")
            changed = True
        if args.write:
            path.write_text(json.dumps(got, indent=1) + "\n")
            print(f"  wrote {path.name}")
    return 1 if changed and not args.write else 0


if __name__ == "__main__":
    raise SystemExit(main())
