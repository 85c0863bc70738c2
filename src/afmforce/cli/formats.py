"""``afmforce formats``: the file formats afmforce reads, from the reader registry.

Per format: identifier (``--format ID``), file endings, what the content must look
like, which library reads it, the deflection unit returned, the metadata taken
from the file, and what the user must give (``--spring-constant``, ...).
"""

from __future__ import annotations

import argparse

from ._outcome import flag_of


def register(sub) -> None:
    p = sub.add_parser("formats", help="list the force-curve file formats afmforce reads",
                       description="The force-curve file formats afmforce reads (from its reader registry): "
                                   "endings, content, what each takes from the file and what the user must give.")
    p.add_argument("--json", action="store_true", help="print the table as JSON")
    p.add_argument("--markdown", action="store_true", help="print the table in Markdown (docs/formats.md)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..io import formats_markdown, formats_table
    from .common import print_json

    rows = formats_table()
    if args.json:
        print_json({"formats": rows})  # one JSON object, like every command
    elif args.markdown:
        print(formats_markdown(), end="")
    else:
        for r in rows:
            print(f"{r['identifier']:<18} {r['name']}")
            print(f"{'':<18} endings: {r['suffixes']}; via {r['via']}; deflection in {r['deflection']}")
            print(f"{'':<18} content: {r['signature']}")
            needs = ", ".join(f"{k} ({flag_of(k)})" for k in r["requires"].split(", ")) if r["requires"] != "-" else "-"
            print(f"{'':<18} from the file: {r['supplies']}; user must give: {needs}")
        print("Give missing metadata with --spring-constant and --sensitivity (afmforce analyze).")
    return 0
