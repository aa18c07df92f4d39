"""What the cross-checks against Byrnes' tmm (crosscheck_tmm.py,
crosscheck_incoherent.py) share: the random wavelength and angle lists their
stacks draw from, and a stack written as irid's TOML."""


def random_lists(rng, grazing_share):
    """1-3 wavelengths in 300-900 nm and 1-3 angles in [0, 89) degrees,
    plus normal incidence one time in five and 89.999 degrees in a further
    `grazing_share` of draws."""
    wavelengths = sorted(float(round(w, 3)) for w in rng.uniform(300.0, 900.0, int(rng.integers(1, 4))))
    angles = [float(round(a, 4)) for a in rng.uniform(0.0, 89.0, int(rng.integers(1, 4)))]
    pick = rng.random()
    if pick < 0.2:
        angles.append(0.0)
    elif pick < 0.2 + grazing_share:
        angles.append(89.999)
    return list(dict.fromkeys(wavelengths)), sorted(set(angles))


def toml_index(z):
    return f"[{z.real!r}, {z.imag!r}]"


def stack_toml(ambient, media, substrate):
    """The stack as irid's TOML: media are (n, thickness_nm) or
    (n, thickness_nm, coherent)."""
    lines = [f"ambient = {{ n = {ambient!r} }}", f"substrate = {{ n = {toml_index(substrate)} }}"]
    for n, d, *coherent in media:
        lines += ["[[layers]]", f"n = {toml_index(n)}", f"thickness_nm = {d!r}"]
        if coherent and not coherent[0]:
            lines.append("coherent = false")
    return "\n".join(lines) + "\n"
