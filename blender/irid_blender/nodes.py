"""The node group's graph: the atlas lookup of export.py's charts in math
nodes (the same closed form as charts.py and the WGSL shader), the
bilinear reads of the tables, the rough table's slices, and the BSDFs. A
node tree is passed in; nothing here creates or removes data-blocks."""

import math

from .export import TABLES


class Builder:
    """Adds nodes and links to a node tree, laid out in columns."""

    def __init__(self, tree):
        self.tree = tree

    def node(self, kind, column, row, label=None, **props):
        node = self.tree.nodes.new(kind)
        node.location = (200.0 * column, -160.0 * row)
        if label:
            node.label = label
        for key, value in props.items():
            setattr(node, key, value)
        return node

    def math(self, operation, column, row, a, b=None, c=None, label=None):
        """A Math node; each operand is an output socket or a constant."""
        node = self.node("ShaderNodeMath", column, row, label, operation=operation)
        for i, operand in enumerate((a, b, c)):
            if operand is None:
                continue
            if isinstance(operand, (int, float)):
                node.inputs[i].default_value = float(operand)
            else:
                self.link(operand, node.inputs[i])
        return node.outputs[0]

    def link(self, output, input_):
        self.tree.links.new(output, input_)


def build_group(group, export, images, ior):
    _group_interface(group.interface, export)
    build = Builder(group)
    inputs = build.node("NodeGroupInput", 0, 0)
    outputs = build.node("NodeGroupOutput", 12, 0)
    geometry = build.node("ShaderNodeNewGeometry", 0, 4)
    x = _thickness_fraction(build, export, inputs)
    normal = _shading_normal(build, inputs, geometry)
    # cos θ: the incoming direction against the shading normal, on the side
    # the light arrives from.
    dot = build.node("ShaderNodeVectorMath", 2, 4, label="cos θ", operation="DOT_PRODUCT")
    build.link(geometry.outputs["Incoming"], dot.inputs[0])
    build.link(normal, dot.inputs[1])
    cos = build.math("ABSOLUTE", 2.5, 4, dot.outputs["Value"])
    # What an atlas's charts read: the thickness in nm, cos θ at most 1.
    span = export.thickness_max_nm - export.thickness_min_nm
    d = build.math("MULTIPLY_ADD", 2, -1, x, span, export.thickness_min_nm, label="thickness nm")
    c = build.math("MINIMUM", 3, 4, cos, 1.0, label="cos θ ≤ 1")
    uv = _atlas_uv(build, export.front, export.size, d, c, 0)
    if export.back is not None and export.back is not export.front:
        # A back face is seen from the substrate: the back side's chart(s).
        # uv = front + backfacing · (back − front): one lookup per image.
        back = _atlas_uv(build, export.back, export.size, d, c, 6 * len(export.front) + 2)
        uv = _blend(build, uv, back, geometry.outputs["Backfacing"], 7.5, 3, "uv of the side")

    # Both tables share the mapping, hence the texels and their weights.
    corners, weights = _texel_corners(build, uv, export.size, 8.5, 1)
    colours = {
        table: _bilinear(build, images[table], corners, weights, 9, 1 + 3 * row, table)
        for row, table in enumerate(TABLES)
    }
    roughness = inputs.outputs["Roughness"] if export.rough is not None else None
    reflectance = colours["reflectance"]
    if roughness is not None:
        reflectance = _rough_reflectance(
            build, export, images["rough"], d, c, roughness, reflectance, geometry
        )
    build.link(reflectance, outputs.inputs["Reflectance"])
    build.link(colours["transmittance"], outputs.inputs["Transmittance"])

    glossy = build.node("ShaderNodeBsdfGlossy", 11.5, -1, label="film reflection", distribution="GGX")
    build.link(reflectance, glossy.inputs["Color"])
    _set_roughness(build, glossy, roughness)
    build.link(normal, glossy.inputs["Normal"])
    build.link(glossy.outputs["BSDF"], outputs.inputs["Reflection"])
    if ior is None:
        build.link(glossy.outputs["BSDF"], outputs.inputs["BSDF"])
        return
    # Cycles' Refraction BSDF takes 1 / IOR on a back face: from the
    # substrate the light refracts into the ambient, and past the critical
    # angle it does not (where the back side's transmittance is 0).
    refraction = build.node(
        "ShaderNodeBsdfRefraction", 11.5, 1, label="film transmission", distribution="GGX"
    )
    refraction.inputs["IOR"].default_value = float(ior)
    build.link(colours["transmittance"], refraction.inputs["Color"])
    _set_roughness(build, refraction, roughness)
    build.link(normal, refraction.inputs["Normal"])
    add = build.node("ShaderNodeAddShader", 12, -1)
    build.link(glossy.outputs["BSDF"], add.inputs[0])
    build.link(refraction.outputs["BSDF"], add.inputs[1])
    build.link(add.outputs["Shader"], outputs.inputs["BSDF"])


def _set_roughness(build, bsdf, roughness):
    """The lobe's GGX roughness: the group's Roughness input, or 0 (mirror)
    in a group without one."""
    if roughness is None:
        bsdf.inputs["Roughness"].default_value = 0.0
    else:
        build.link(roughness, bsdf.inputs["Roughness"])


def _texel_corners(build, uv, texture_size, column, row):
    """The centres of the four texels around image coordinates uv, and the
    weights between them (fractions along u and v): the bilinear filter's
    inputs, computed in nodes so that every engine reads the same texels.
    A texture unit's own linear filter would be the same numbers in Cycles,
    but EEVEE's samples a mip level and anisotropic footprint chosen from
    the screen-space derivatives of uv, which jump where the lookup changes
    charts and grow at grazing angles: a seam at chart borders and speckles
    at a sphere's rim."""
    split = build.node("ShaderNodeSeparateXYZ", column, row, label="u, v")
    build.link(uv, split.inputs["Vector"])
    centres, weights = [], []
    for k, (axis, size) in enumerate(zip("XY", texture_size)):
        at = row + 0.5 * k
        # Texel coordinates with texel i's centre at i: t = u · size − ½.
        t = build.math("MULTIPLY_ADD", column + 0.5, at, split.outputs[axis], float(size), -0.5)
        weight = build.math("FRACT", column + 1, at, t, label=f"weight along {axis}")
        first = build.math("SUBTRACT", column + 1.5, at, t, weight, label=f"first texel along {axis}")
        low = build.math("MULTIPLY_ADD", column + 2, at, first, 1.0 / size, 0.5 / size)
        high = build.math("ADD", column + 2.5, at, low, 1.0 / size)
        centres.append((low, high))
        weights.append(weight)
    corners = []
    for v in centres[1]:
        for u in centres[0]:
            corner = build.node("ShaderNodeCombineXYZ", column + 3, row + 0.5 * len(corners))
            build.link(u, corner.inputs["X"])
            build.link(v, corner.inputs["Y"])
            corners.append(corner.outputs["Vector"])
    return corners, weights


def _bilinear(build, image, corners, weights, column, row, label):
    """The image's bilinear interpolation from its four texels at `corners`
    (from _texel_corners), each read at its centre with Closest
    interpolation (no filtering, no mip level), blended in math nodes."""
    reads = []
    for k, corner in enumerate(corners):
        tex = build.node(
            "ShaderNodeTexImage",
            column,
            row + 0.5 * k,
            label=f"{label} texel {k}",
            interpolation="Closest",
            extension="EXTEND",
            projection="FLAT",
        )
        tex.image = image
        build.link(corner, tex.inputs["Vector"])
        reads.append(tex.outputs["Color"])
    along_u, along_v = weights
    low = _blend(build, reads[0], reads[1], along_u, column + 0.5, row, f"{label} lower row")
    high = _blend(build, reads[2], reads[3], along_u, column + 0.5, row + 1, f"{label} upper row")
    return _blend(build, low, high, along_v, column + 2, row + 0.5, label)


def _blend(build, a, b, weight, column, row, label):
    """a + weight · (b − a) for vector (or colour) sockets and a float socket
    weight: b where weight is 1, exactly a where it is 0."""
    step = build.node("ShaderNodeVectorMath", column, row, label="b − a", operation="SUBTRACT")
    build.link(b, step.inputs[0])
    build.link(a, step.inputs[1])
    scale = build.node("ShaderNodeVectorMath", column + 0.5, row, label="× weight", operation="SCALE")
    build.link(step.outputs["Vector"], scale.inputs[0])
    build.link(weight, scale.inputs["Scale"])
    total = build.node("ShaderNodeVectorMath", column + 1, row, label=label, operation="ADD")
    build.link(a, total.inputs[0])
    build.link(scale.outputs["Vector"], total.inputs[1])
    return total.outputs["Vector"]


def _rough_reflectance(build, export, image, d, c, roughness, smooth, geometry):
    """The reflection lobe's colour: F_eff from the rough table where the
    roughness is above 0, exactly the smooth film's reflectance (`smooth`)
    where it is 0. As irid_film_rough (shaders/irid_film_rough.wgsl): the
    rough atlas's chart lookup at thickness d nm and cos θ c (the smooth
    atlas's closed form, _atlas_uv), the slice position s = √roughness ·
    (S − 1), one bilinear lookup in each of the two slices around it (the
    chart's coordinates moved to the slice's rectangle), blended linearly.
    The table holds light from the ambient: a back face of a film with a
    distinct back side keeps the back chart's smooth reflectance at the view
    angle (docs/blender.md)."""
    rough = export.rough
    top = 14 + 6 * len(export.charts)  # below the smooth lookups' nodes
    # Blender's square root is 0 below 0; the clamp takes a roughness above 1 to 1.
    root = build.math("SQRT", 1, top, roughness, label="√roughness, clamped")
    root.node.use_clamp = True
    s = build.math("MULTIPLY", 2, top, root, float(rough.slices - 1), label="slice position")
    s0 = build.math("MINIMUM", 3, top, build.math("FLOOR", 2.5, top, s), float(rough.slices - 2),
                    label="slice below")
    weight = build.math("SUBTRACT", 3.5, top, s, s0, label="weight of the slice above")
    s1 = build.math("ADD", 3.5, top + 1, s0, 1.0, label="slice above")
    # The rough atlas's own thickness range (irid_film_rough clamps to it).
    clamp = build.node("ShaderNodeClamp", 2.5, top + 4, label="thickness in the rough atlas")
    build.link(d, clamp.inputs["Value"])
    clamp.inputs["Min"].default_value = rough.thickness_min_nm
    clamp.inputs["Max"].default_value = rough.thickness_max_nm
    uv = _atlas_uv(build, rough.charts, rough.size, clamp.outputs["Result"], c, top + 4)
    colours = []
    for k, slice_ in enumerate((s0, s1)):
        at = top + 2 + 2 * k
        moved = build.node("ShaderNodeVectorMath", 8.5, at, label="uv in the slice", operation="ADD")
        build.link(uv, moved.inputs[0])
        build.link(_slice_offset(build, rough, slice_, at), moved.inputs[1])
        corners, weights = _texel_corners(build, moved.outputs["Vector"], rough.size, 6.5, at)
        label = f"rough slice {'above' if k else 'below'}"
        colours.append(_bilinear(build, image, corners, weights, 9, at, label))
    f_eff = _blend(build, colours[0], colours[1], weight, 9.5, top + 3, "F_eff")
    use = build.math("GREATER_THAN", 9.5, top, roughness, 0.0, label="rough")
    if not export.rough_applies_to_back_faces():
        front = build.math("SUBTRACT", 9.5, top + 1, 1.0, geometry.outputs["Backfacing"])
        use = build.math("MULTIPLY", 10, top + 1, use, front, label="rough, front face")
    return _blend(build, smooth, f_eff, use, 10.5, top + 2, "reflectance of the lobe")


def _group_interface(iface, export):
    """The node group's sockets (docs/blender.md lists them)."""
    sock = iface.new_socket("Thickness", in_out="INPUT", socket_type="NodeSocketFloat")
    sock.subtype = "FACTOR"
    sock.min_value, sock.max_value, sock.default_value = 0.0, 1.0, 0.5
    sock.description = (
        f"Film thickness: 0 = {export.thickness_min_nm:g} nm, 1 = {export.thickness_max_nm:g} nm "
        "(used while Thickness nm is below 0)"
    )
    sock = iface.new_socket("Thickness nm", in_out="INPUT", socket_type="NodeSocketFloat")
    sock.min_value, sock.max_value, sock.default_value = -1.0, 1.0e6, -1.0
    sock.description = (
        f"Film thickness in nm, clamped to {export.thickness_min_nm:g}-"
        f"{export.thickness_max_nm:g} nm; below 0 (the default), the 0-1 Thickness input is used"
    )
    if export.rough is not None:
        sock = iface.new_socket("Roughness", in_out="INPUT", socket_type="NodeSocketFloat")
        sock.subtype = "FACTOR"
        sock.min_value, sock.max_value, sock.default_value = 0.0, 1.0, 0.0
        sock.description = (
            "GGX roughness of both lobes; above 0 the reflection's colour is the film's "
            "F_eff from the export's rough table"
        )
    sock = iface.new_socket("Normal", in_out="INPUT", socket_type="NodeSocketVector")
    sock.hide_value = True
    sock.description = (
        "Shading normal of the film's angle and of both lobes (a normal map, a "
        "Principled coat's normal); unlinked, the surface's own"
    )
    iface.new_socket("BSDF", in_out="OUTPUT", socket_type="NodeSocketShader")
    sock = iface.new_socket("Reflection", in_out="OUTPUT", socket_type="NodeSocketShader")
    sock.description = "The reflection lobe alone, for layering over another shader"
    for table in ("Reflectance", "Transmittance"):
        iface.new_socket(table, in_out="OUTPUT", socket_type="NodeSocketColor")


def _thickness_fraction(build, export, inputs):
    """The thickness as a fraction of the export's range, clamped: from
    Thickness nm when it is 0 or more, else the 0-1 Thickness input."""
    span = export.thickness_max_nm - export.thickness_min_nm
    scale = 1.0 / span if span > 0.0 else 0.0
    nm = inputs.outputs["Thickness nm"]
    from_nm = build.math("MULTIPLY_ADD", 0.5, -1, nm, scale, -export.thickness_min_nm * scale)
    use_nm = build.math("GREATER_THAN", 0.5, -2, nm, -0.5, label="Thickness nm given")
    towards = build.math("SUBTRACT", 1, -1, from_nm, inputs.outputs["Thickness"])
    x = build.math(
        "MULTIPLY_ADD", 1.5, -1, use_nm, towards, inputs.outputs["Thickness"], label="x = clamp(thickness)"
    )
    x.node.use_clamp = True
    return x


def _shading_normal(build, inputs, geometry):
    """The Normal input, normalized, when it is linked (not zero); else the
    surface's shading normal."""
    given = inputs.outputs["Normal"]
    length = build.node("ShaderNodeVectorMath", 0.5, 6, operation="LENGTH")
    build.link(given, length.inputs[0])
    linked = build.math("GREATER_THAN", 1, 6, length.outputs["Value"], 1e-6, label="Normal linked")
    unit = build.node("ShaderNodeVectorMath", 0.5, 7, operation="NORMALIZE")
    build.link(given, unit.inputs[0])
    step = build.node("ShaderNodeVectorMath", 1, 7, operation="SUBTRACT")
    build.link(unit.outputs["Vector"], step.inputs[0])
    build.link(geometry.outputs["Normal"], step.inputs[1])
    scale = build.node("ShaderNodeVectorMath", 1.5, 7, operation="SCALE")
    build.link(step.outputs["Vector"], scale.inputs[0])
    build.link(linked, scale.inputs["Scale"])
    normal = build.node("ShaderNodeVectorMath", 2, 6, label="shading normal", operation="ADD")
    build.link(geometry.outputs["Normal"], normal.inputs[0])
    build.link(scale.outputs["Vector"], normal.inputs[1])
    return normal.outputs["Vector"]


def _uv(build, x, y, origin, size, texture_size, row):
    """The image coordinates of chart point (x, y) in the rectangle of nodes
    whose first node is texel `origin` and whose size is `size` texels:
    node i at the centre of texel origin + i, so u = (x0 + 0.5 + x (w − 1))
    / W; Blender puts an image file's first row at v = 1, so the texture is
    read at 1 − v."""
    width, height = texture_size
    (x0, y0), (w, h) = origin, size
    u = build.math("MULTIPLY_ADD", 6.5, row, x, (w - 1) / width, (x0 + 0.5) / width, label="u")
    v = build.math(
        "MULTIPLY_ADD", 6.5, row + 1, y, -(h - 1) / height, 1.0 - (y0 + 0.5) / height,
        label="v (Blender)",
    )
    uv = build.node("ShaderNodeCombineXYZ", 7, row, label="uv")
    build.link(u, uv.inputs["X"])
    build.link(v, uv.inputs["Y"])
    return uv.outputs["Vector"]


def _atlas_uv(build, charts, atlas_size, d, c, row):
    """Version 3: the image coordinates of thickness d (nm, inside the
    range) at cos θ c (in [0, 1]) in the chart of `charts` (one side's, in
    the choice rule's order) that serves them. Every chart's (u, v) is
    computed, then chosen in closed form as the shader does: the first
    chart that serves (d, c), else the side's last band; one image lookup
    follows."""
    found = []
    for k, chart in enumerate(charts):
        at = row + 6 * k
        if chart.kind == "corner":
            x, y, serves = _corner_xy(build, chart, d, c, at)
        else:
            x, y = _band_xy(build, chart, d, c, at)
            serves = build.math("SUBTRACT", 4, at + 5, 1.0, build.math(
                "GREATER_THAN", 3.5, at + 5, c, chart.cos_hi), label=f"c ≤ {chart.cos_hi:.4g}")
        found.append((chart, serves, _uv(build, x, y, chart.rect[:2], chart.rect[2:], atlas_size, at)))
    last = max(k for k, (chart, _, _) in enumerate(found) if chart.kind == "band")
    uv = found[last][2]
    # From the last chart back to the first, each that serves replaces what
    # follows it: the first that serves wins.
    for k in reversed(range(last)):
        uv = _blend(build, uv, found[k][2], found[k][1], 8, row + 6 * k + 3, f"chart {k} serves")
    return uv


def _optical(build, chart, d, c, column, row):
    """p = d · s(c), s(c) = √max(1 − a (1 − c²), floor²): the optical
    thickness along which a band's fringes run."""
    if chart.a == 0.0:
        return d  # s = 1 (floor ≤ 1)
    t = build.math("MULTIPLY_ADD", column, row, build.math("MULTIPLY", column - 0.5, row, c, c),
                   chart.a, 1.0 - chart.a, label="1 − a (1 − c²)")
    s = build.math("SQRT", column + 1, row, build.math("MAXIMUM", column + 0.5, row, t,
                                                      chart.floor ** 2), label="s(c)")
    return build.math("MULTIPLY", column + 1.5, row, d, s, label="p = d s(c)")


def _log_e(build, value, column, row, label=None):
    """ln(value) (Blender's logarithm: 0 for value ≤ 0)."""
    return build.math("LOGARITHM", column, row, value, math.e, label=label)


def _band_xy(build, chart, d, c, row):
    """A band's (x, y): p on its log (or uniform) axis, cos θ (clamped to
    the band) on its warped axis, both clamped to [0, 1]."""
    clamp = build.node("ShaderNodeClamp", 3, row + 2, label="clamp to the band")
    build.link(c, clamp.inputs["Value"])
    clamp.inputs["Min"].default_value = chart.cos_lo
    clamp.inputs["Max"].default_value = chart.cos_hi
    ck = clamp.outputs["Result"]
    p = _optical(build, chart, d, ck, 4, row)
    u0, u1 = chart.p_warp(chart.p_lo_nm), chart.p_warp(chart.p_hi_nm)
    if u1 > u0:
        w = p
        if chart.p0_nm > 0.0:
            w = _log_e(build, build.math("MULTIPLY_ADD", 5.5, row, p, 1.0 / chart.p0_nm, 1.0), 6, row,
                       label="ln(1 + p / p0)")
        x = build.math("MULTIPLY_ADD", 6.5, row, w, 1.0 / (u1 - u0), -u0 / (u1 - u0), label="x")
        x.node.use_clamp = True
    else:
        x = build.math("MULTIPLY", 6.5, row, p, 0.0, label="x = 0 (one thickness)")
    v0, v1 = chart.c_warp(chart.cos_lo), chart.c_warp(chart.cos_hi)
    if v1 > v0:
        sign = chart.sign()
        t = build.math("MULTIPLY_ADD", 4, row + 1, ck, sign, -sign * chart.anchor, label="|c − anchor|")
        t = build.math("MAXIMUM", 4.5, row + 1, t, 0.0)
        if chart.offset > 0.0:
            g = _log_e(build, build.math("ADD", 5, row + 1, t, chart.offset), 5.5, row + 1)
        elif chart.offset == 0.0:
            g = build.math("SQRT", 5.5, row + 1, t)
        else:
            g = t
        # y = (σ g − W(lo)) / (W(hi) − W(lo))
        y = build.math("MULTIPLY_ADD", 6.5, row + 1, g, sign / (v1 - v0), -v0 / (v1 - v0), label="y")
        y.node.use_clamp = True
    else:
        y = build.math("MULTIPLY", 6.5, row + 1, ck, 0.0, label="y = 0 (one angle)")
    return x, y


def _corner_xy(build, chart, d, c, row):
    """The corner's polar (x, y) about zero thickness at grazing incidence,
    P = p / scale, ρ = √(P² + c²), φ = atan2(P, c): x = φ / (π/2), y = ρ /
    radius; and whether it serves (ρ < radius)."""
    pp = build.math("MULTIPLY", 5.5, row, _optical(build, chart, d, c, 4, row), 1.0 / chart.scale_nm,
                    label="P")
    rho = build.math("SQRT", 6.5, row + 1, build.math(
        "MULTIPLY_ADD", 6, row + 1, c, c, build.math("MULTIPLY", 5.5, row + 1, pp, pp)), label="ρ")
    phi = build.math("ARCTAN2", 6, row, pp, c, label="φ")
    x = build.math("MULTIPLY", 6.5, row, phi, 2.0 / math.pi, label="x")
    x.node.use_clamp = True
    y = build.math("MULTIPLY", 7, row + 1, rho, 1.0 / chart.radius, label="y")
    y.node.use_clamp = True
    serves = build.math("LESS_THAN", 7, row + 2, rho, chart.radius, label="ρ < radius")
    return x, y, serves


def _slice_offset(build, rough, slice_, row):
    """How far slice `slice_` (a float socket holding a whole number) lies
    from the texture's corner, in image coordinates: slices lie in rows of
    `columns`, slice s at (gutter + (s mod columns) · pitch_x, gutter +
    ⌊s / columns⌋ · pitch_y) texels; the half keeps the row off a rounding
    edge, as in the shader. Blender's v runs up the image, so the offset's
    v is negative."""
    columns = float(rough.columns)
    width, height = rough.size
    slice_row = build.math("FLOOR", 4, row, build.math("DIVIDE", 3.5, row, build.math(
        "ADD", 3, row, slice_, 0.5), columns), label="slice row")
    column = build.math("MULTIPLY_ADD", 4.5, row, slice_row, -columns, slice_, label="slice column")
    du = build.math("MULTIPLY_ADD", 5, row, column, rough.pitch[0] / width, rough.gutter / width,
                    label="slice u")
    dv = build.math("MULTIPLY_ADD", 5, row + 1, slice_row, -rough.pitch[1] / height,
                    -rough.gutter / height, label="slice v")
    offset = build.node("ShaderNodeCombineXYZ", 5.5, row, label="slice offset")
    build.link(du, offset.inputs["X"])
    build.link(dv, offset.inputs["Y"])
    return offset.outputs["Vector"]
