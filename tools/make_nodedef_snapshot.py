#!/usr/bin/env python
"""Write openpbr_diffuse/data/materialx_nodedefs.json from the installed MaterialX library.

The snapshot is the fallback of openpbr_diffuse.nodes.materialx_defs when the MaterialX
package cannot be imported: the input names, types, default value strings,
defaultgeomprops, uniform flags and ui ranges of the nodedefs in ``NODEDEFS``, exactly as
the MaterialX data library declares them.  tests/test_nodes_interface.py checks that it
still equals the installed library.

Usage:  python tools/make_nodedef_snapshot.py
"""

import datetime
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from openpbr_diffuse.nodes.materialx_defs import SNAPSHOT_FILE, snapshot_records  # noqa: E402


def main():
    records, source = snapshot_records()
    snap = {
        "source": source,
        "generated": datetime.date.today().isoformat(),
        "command": "python tools/make_nodedef_snapshot.py",
        "nodedefs": records,
    }
    with open(SNAPSHOT_FILE, "w") as fh:
        json.dump(snap, fh, indent=1)
        fh.write("\n")
    print(f"wrote {SNAPSHOT_FILE} from {source}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
