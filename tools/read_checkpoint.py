#!/usr/bin/env python3
"""Reads a powder checkpoint (format 21: a NumPy .npz archive) and prints what it holds.

    python3 tools/read_checkpoint.py out/cohesive_cluster/checkpoint.bin [--array NAME]

The checkpoint is an ordinary .npz: `numpy.load(path)` opens it, `powder.json` is its
header, every other member a named array (see docs/checkpoints.md). This reader refuses
other formats by name, as powder does. Needs NumPy (`apt-get install python3-numpy`).
"""

import argparse
import json
import sys
import zipfile

import numpy as np

FORMAT = 21


def load(path):
    """The header (a dict) and the archive (numpy's NpzFile) of the checkpoint at `path`."""
    with open(path, "rb") as f:
        opening = f.read(8)
    if opening == b"POWDERCK":
        sys.exit(f"{path}: written by an older powder (format 16 or earlier, bincode); "
                 f"this reader reads format {FORMAT}")
    try:
        archive = np.load(path, allow_pickle=False)
        header = json.loads(archive["powder.json"])
    except Exception as e:  # not a zip, or no header: not ours
        sys.exit(f"{path} is not a powder checkpoint (or is damaged): {e}")
    if header.get("magic") != "powder-checkpoint":
        sys.exit(f"{path} is not a powder checkpoint")
    if header.get("format") != FORMAT:
        sys.exit(f"{path}: format {header.get('format')} (powder {header.get('version')}); "
                 f"this reader reads format {FORMAT}")
    return header, archive


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("checkpoint")
    ap.add_argument("--array", help="print this array's values")
    a = ap.parse_args()
    header, archive = load(a.checkpoint)
    print(json.dumps(header))
    try:
        for name in archive.files:
            if name.endswith(".json"):
                continue
            v = archive[name]
            print(f"{name}: {v.dtype.descr if v.dtype.names else v.dtype.str} shape {v.shape}")
        if a.array:
            if a.array not in archive.files:
                sys.exit(f"no array {a.array!r}; the checkpoint holds {', '.join(archive.files)}")
            v = archive[a.array]
            np.set_printoptions(precision=17, threshold=sys.maxsize)
            print(v if v.dtype.names is None else "\n".join(str(r) for r in v))
    except (zipfile.BadZipFile, ValueError, EOFError) as e:
        sys.exit(f"{a.checkpoint} is damaged: {e}")


if __name__ == "__main__":
    main()
