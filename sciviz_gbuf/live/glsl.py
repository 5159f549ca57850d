"""GLSL of the GPU route (:mod:`.gpu`): three full-screen fragment passes over the depth of the
frame being drawn, the same operators as the CPU route's :mod:`sciviz_gbuf.core.frame` and
:func:`sciviz_gbuf.filters.edge_map`, statement for statement.

1. ``GBUFFER_FS``: the window depth ``d``, read from the window's own depth texture (no copy;
   sample 0 of a multisampled one), is unprojected into the linear eye depth with the
   camera's clip matrix, Saito's ``sz`` follows (1990 Eq. 6: ``d^2 / (w z)`` in perspective,
   ``(2 d - z) / w`` in parallel projection, ``d`` the camera distance, ``w`` the focal-plane
   pixel), and the normal from the eye-space positions of the pixel and its neighbours: per
   axis the one-sided difference towards the side that continues the surface (the smaller
   second difference of ``sz``), so a pixel next to a crease takes its own face's normal
   (Nienhaus & Döllner 2003 §3 render the normal and depth maps). Output ``(n, sz)``, zero
   off the surface (a unit normal is never zero).
2. ``EDGE_FS``: the 2003 edge map (§4.1). Inner intensity from the smaller cosine of the two
   diagonal normal pairs, ramped from ``crease`` to ``1.5 crease`` degrees; profile
   ``1 - I_Z``, ``I_Z = (1 - |A-H|/2)^2 (1 - |C-F|/2)^2`` (operator 0, diagonal) or the
   C1 sum over the 8 neighbours (operator 1; 1990 Eq. 9), the pairs' jumps measured as the
   step of ``sz`` not explained by the one-sided slopes on either side, in pixel footprints,
   relative to the grazing angle (``edges._pair_gap``).
3. ``COMPOSITE_FS``: the lines widened by a disk (``edges._dilate``'s footprint), the style's
   colours and opacity, composited over the subplot by the GL blend
   ``src a + dst (1 - a)``: inner edges first, profiles over them, as
   :func:`sciviz_gbuf.live.overlay.overlay_rgba`.

Every parameter is a uniform: changing one never compiles a program. Each shader reads
``texCoord`` once so that the quad helper's texture-coordinate attribute stays bound (an
unused input is optimised away and VTK reports the missing attribute).
"""

from __future__ import annotations

__all__ = [
    "COMPOSITE_FS",
    "CONTOUR_FEATURES",
    "CONTOUR_FS_DEC",
    "CONTOUR_VS_DEC_HEIGHT",
    "CONTOUR_VS_DEC_SCALAR",
    "CONTOUR_VS_IMPL_HEIGHT",
    "CONTOUR_VS_IMPL_SCALAR",
    "EDGE_FS",
    "GBUFFER_FS",
    "contour_fs_impl",
    "gbuffer_fs",
]

_HEAD = """//VTK::System::Dec
//VTK::Output::Dec
in vec2 texCoord;
uniform ivec2 size;
uniform int parallel;
uniform float dist;
uniform float pixel;
bool inside(ivec2 q) { return q.x >= 0 && q.y >= 0 && q.x < size.x && q.y < size.y; }
"""


GBUFFER_FS = (
    _HEAD
    + """uniform sampler2D zTex;  // the window's own depth attachment
uniform ivec2 origin;    // the subplot's lower-left pixel in the window
uniform vec4 proj;  // the clip matrix's [2][2], [2][3], [3][2], [3][3]
const float HUGE = 1e30;

// eye depth e and sz of pixel q; false off the surface (depth 1: nothing drawn)
bool surf(ivec2 q, out float e, out float s)
{
  e = 0.0;
  s = 0.0;
  if (!inside(q)) return false;
  float d = texelFetch(zTex, q + origin, 0).r;
  if (!(d >= 0.0 && d < 1.0)) return false;
  float zn = 2.0 * d - 1.0;
  e = -(proj.y - zn * proj.w) / (zn * proj.z - proj.x);
  if (!(e > 0.0 && e < HUGE)) return false;
  s = parallel != 0 ? (2.0 * dist - e) / pixel : dist * dist / (pixel * e);
  return true;
}

vec3 pos(ivec2 q, float e)
{
  float k = parallel != 0 ? 1.0 : e / dist;
  return vec3((float(q.x) + 0.5 - 0.5 * float(size.x)) * k,
              (float(q.y) + 0.5 - 0.5 * float(size.y)) * k, -e / pixel);
}

// how well a neighbour (s1) continues the surface of a pixel with sz x: the second difference
// with the one beyond it (s2), the first if that one is missing, HUGE if it is missing itself
float sideError(bool ok1, float s1, bool ok2, float s2, float x)
{
  if (!ok1) return HUGE;
  if (!ok2) return abs(s1 - x) * 1e6;
  return abs(2.0 * s1 - x - s2);
}

// the tangent along axis a (one pixel step), from the side that continues the surface
vec3 tangent(ivec2 q, ivec2 a, vec3 p, float x, vec3 fallback)
{
  float e1, s1, e2, s2, e3, s3, e4, s4;
  bool f1 = surf(q + a, e1, s1);
  bool f2 = surf(q + 2 * a, e2, s2);
  bool b1 = surf(q - a, e3, s3);
  bool b2 = surf(q - 2 * a, e4, s4);
  float ef = sideError(f1, s1, f2, s2, x);
  float eb = sideError(b1, s3, b2, s4, x);
  if (ef < HUGE && ef <= eb) return pos(q + a, e1) - p;
  if (eb < HUGE) return p - pos(q - a, e3);
  return fallback;
}

void main()
{
  if (texCoord.x < -1.0) discard;
  ivec2 q = ivec2(gl_FragCoord.xy);
  float e, x;
  if (!surf(q, e, x))
  {
    gl_FragData[0] = vec4(0.0);
    return;
  }
  vec3 p = pos(q, e);
  vec3 t = tangent(q, ivec2(1, 0), p, x, vec3(1.0, 0.0, 0.0));
  vec3 u = tangent(q, ivec2(0, 1), p, x, vec3(0.0, 1.0, 0.0));  // +y: the row above
  vec3 n = cross(t, u);  // x right, y up: towards the viewer
  float l = length(n);
  n = (l > 0.0 && l < HUGE) ? n / l : vec3(0.0, 0.0, 1.0);
  gl_FragData[0] = vec4(n, x);
}
"""
)


def gbuffer_fs(multisampled: bool) -> str:
    """``GBUFFER_FS`` reading a depth texture with several samples per pixel (sample 0) or one."""
    return GBUFFER_FS.replace("sampler2D zTex", "sampler2DMS zTex") if multisampled else GBUFFER_FS


EDGE_FS = (
    _HEAD
    + """uniform sampler2D gTex;
uniform float jump;    // depth_jump, pixel footprints
uniform float crease;  // crease_angle, degrees
uniform int operator;  // 0 diagonal, 1 c1
uniform int inner_on;  // 0: profiles only (style "profile")

// one pixel of the G texture, fetched once: inside the image, on the surface, sz, normal
struct Px { bool inside; bool ok; float sz; vec3 n; };

Px fetch(ivec2 q)
{
  Px p;
  p.inside = inside(q);
  vec4 t = p.inside ? texelFetch(gTex, q, 0) : vec4(0.0);
  p.n = t.xyz;
  p.sz = t.w;
  p.ok = p.inside && dot(t.xyz, t.xyz) > 0.5;  // a unit normal; zero off the surface
  return p;
}

float eyeDepth(float s)
{
  return parallel != 0 ? 2.0 * dist - s * pixel : dist * dist / (pixel * s);
}

// the step of sz from p to p2 not explained by the one-sided slopes from a (before p) and
// b (after p2), in pixel footprints, relative to the grazing angle (edges._pair_gap)
float pairGap(Px a, Px p, Px p2, Px b)
{
  if (!(a.ok && b.ok)) return 0.0;  // a side without slope: no evidence of a step
  float sl = p.sz - a.sz;
  float sr = b.sz - p2.sz;
  float j = p2.sz - p.sz;
  float lo = min(sl, sr);
  float hi = max(sl, sr);
  float gap = j < lo ? lo - j : (j > hi ? j - hi : 0.0);
  if (gap == 0.0) return 0.0;
  float scale = parallel != 0 ? 1.0 : min(eyeDepth(p.sz), eyeDepth(p2.sz)) / dist;
  float s = min(abs(sl), abs(sr)) * scale;  // the gentler slope: depth noise grows with it
  return gap * scale / sqrt(1.0 + s * s);
}

// discontinuity strength in [0, 1] of the pair (p, p2): 1 across the coverage outline
float pairJump(Px a, Px p, Px p2, Px b)
{
  if (!(p.inside && p2.inside)) return 0.0;  // the image border is not an edge
  if (p.ok != p2.ok) return 1.0;
  if (!p.ok) return 0.0;
  return clamp((pairGap(a, p, p2, b) - jump) / jump, 0.0, 1.0);
}

void main()
{
  if (texCoord.x < -1.0) discard;
  ivec2 q = ivec2(gl_FragCoord.xy);
  Px c = fetch(q);
  float prof;
  float cmin = 1.0;
  if (operator == 1)
  {
    // 1990 Eq. 9 over the 8 neighbours (in turn around the pixel, so the opposite of k is
    // k + 4), weight 2 on the 4-neighbours, scaled so that a straight step gives 1
    ivec2 dirs[8] = ivec2[8](ivec2(1, 0), ivec2(1, 1), ivec2(0, 1), ivec2(-1, 1),
                             ivec2(-1, 0), ivec2(-1, -1), ivec2(0, -1), ivec2(1, -1));
    Px ring[8];
    for (int k = 0; k < 8; ++k) ring[k] = fetch(q + dirs[k]);
    float total = 0.0;
    for (int k = 0; k < 8; ++k)
    {
      float wgt = (k % 2 == 0) ? 2.0 : 1.0;
      total += wgt * pairJump(ring[(k + 4) % 8], c, ring[k], fetch(q + 2 * dirs[k]));
    }
    prof = min(1.0, 2.0 * total / 8.0);
    for (int k = 1; k < 4; k += 2)
      if (ring[k].ok && ring[k + 4].ok) cmin = min(cmin, dot(ring[k].n, ring[k + 4].n));
  }
  else
  {
    // |A - H| and |C - F|: a jump on either half of each diagonal through the pixel
    float iz = 1.0;
    for (int k = 0; k < 2; ++k)
    {
      ivec2 d = k == 0 ? ivec2(1, 1) : ivec2(1, -1);
      Px m2 = fetch(q - 2 * d);
      Px m1 = fetch(q - d);
      Px p1 = fetch(q + d);
      Px p2 = fetch(q + 2 * d);
      float s = 1.0 - max(pairJump(m2, m1, c, p1), pairJump(m1, c, p1, p2));
      iz *= s * s;
      if (m1.ok && p1.ok) cmin = min(cmin, dot(m1.n, p1.n));
    }
    prof = 1.0 - iz;
  }
  float inner = 0.0;
  if (inner_on != 0 && c.ok)
  {
    // the smaller cosine of the diagonal pairs: the one crossing an edge along a diagonal
    float ang = degrees(acos(clamp(cmin, -1.0, 1.0)));
    inner = clamp((ang - crease) / (0.5 * crease), 0.0, 1.0);
  }
  gl_FragData[0] = vec4(inner, prof, 0.0, 1.0);
}
"""
)


COMPOSITE_FS = (
    _HEAD
    + """uniform sampler2D eTex;
uniform ivec2 origin;  // the subplot's lower-left pixel in the window
uniform int foot;      // the disk's diameter in pixels (1: no widening)
uniform float opacity;
uniform vec3 innerColor;
uniform vec3 profileColor;

void main()
{
  if (texCoord.x < -1.0) discard;
  ivec2 q = ivec2(gl_FragCoord.xy) - origin;
  vec2 v = vec2(0.0);
  if (foot <= 1)
  {
    v = texelFetch(eTex, q, 0).xy;
  }
  else
  {
    // grey dilation by the disk whose extent across any line direction is foot pixels
    int o = (foot - 1) / 2;
    float c = 0.5 * float(foot - 1);
    float r2 = 0.25 * float(foot * foot);
    for (int a = 0; a < foot; ++a)
      for (int b = 0; b < foot; ++b)
      {
        float dy = float(a) - c;
        float dx = float(b) - c;
        if (dx * dx + dy * dy > r2) continue;
        ivec2 s = q + ivec2(b - o, o - a);  // ink[r + a - o, c + b - o]; rows run up here
        if (inside(s)) v = max(v, texelFetch(eTex, s, 0).xy);
      }
  }
  float i = clamp(v.x, 0.0, 1.0) * opacity;
  float p = clamp(v.y, 0.0, 1.0) * opacity;
  float a = i + p - i * p;  // 1 - (1 - i)(1 - p): inner edges first, profiles over them
  if (a <= 0.0) discard;
  gl_FragData[0] = vec4((p * profileColor + i * (1.0 - p) * innerColor) / a, a);
}
"""
)


# --------------------------------------------------------------------------- contour lines
#
# Replacements in the actor's own shaders (vtkShaderProperty), so the lines cost one pass:
# the field goes from the vertex shader to the fragment shader as a varying (a point array
# mapped to the vertex attribute ``sgContourScalar``, or the world height unprojected from
# the clip position with the camera's inverse), and the fragment shader draws
# :func:`sciviz_gbuf.filters.contour_lines`' Eq. 7-15 after VTK's lighting. The gradient of
# Eq. 9 is the field's screen-space derivative: exact for the interpolated field, which is
# linear across each triangle. The uniforms (``sg*``) are declared by VTK from the shader
# property's custom uniforms.

CONTOUR_VS_DEC_SCALAR = """//VTK::Normal::Dec
in float sgContourScalar;
out float sgContourField;
"""
CONTOUR_VS_DEC_HEIGHT = """//VTK::Normal::Dec
out float sgContourField;
"""
CONTOUR_VS_IMPL_SCALAR = """//VTK::Normal::Impl
  sgContourField = sgContourScalar;
"""
CONTOUR_VS_IMPL_HEIGHT = """//VTK::Normal::Impl
  {
    // world height from the clip position: VTK's model matrix and coordinate shift are in it
    vec4 sgClip = MCDCMatrix * vertexMC;
    sgContourField = dot(sgHeightNum, sgClip) / dot(sgHeightDen, sgClip);
  }
"""

CONTOUR_FS_DEC = """//VTK::Normal::Dec
in float sgContourField;
"""

#: What a set of line parameters needs of the fragment shader (:func:`contour_fs_impl`).
CONTOUR_FEATURES = ("major", "poly", "cap", "sparse", "dense", "cdense", "beyond")


def _fade(value: str, weight: str, target: str | None) -> str:
    """``value`` faded by ``weight`` towards ``target`` (Eq. 11 and 15), or towards 0."""
    if target is None:
        return f"    {value} *= {weight};"
    return f"    {value} = {weight} * {value} + (1.0 - {weight}) * {target};"


def contour_fs_impl(features: frozenset[str] | set[str]) -> str:
    """The fragment replacement drawing the lines with the parts of Eq. 7-15 the parameters
    use, after VTK's lighting (``//VTK::Light::Impl``).

    llvmpipe runs both sides of every branch (masked SIMD) and each operation costs about
    0.2 % of a plain frame there, so the program holds only the parts in use and takes the
    products of uniforms ready-made: ``major`` (a major family, ``major_q > 0``), ``poly``
    (a profile other than ``linear``: ``P(v) = v (p1 + v (p2 + v p3))``, else ``P(v) = v``),
    ``cap`` (a line narrower than a pixel: its peak ``cap < 1``), ``sparse`` (``c_sparse >
    0``: the flat fade of Eq. 11 goes to it, else to 0), ``dense`` (the dense-line fade of
    Eq. 15), ``cdense`` (``c_dense > 0``), ``beyond`` (Eq. 13-14's second term, the ink of
    the level beyond the nearest). Each set of parts is one program (compiled once, kept by
    VTK's shader cache); within one, every value is a uniform.

    The uniforms: ``sgQB = q b`` (per family, so ``t b = frac q b / g`` with ``t`` the
    distance in px to the level and ``b`` the profile's slope), ``sgDenseK1 = q / d``,
    ``sgDenseK0 = 1 - dense_at / d`` (Eq. 15's ramp ``clip((q / g - dense_at) / d + 1)``)
    and those of :func:`~sciviz_gbuf.filters.contour_line_parameters` (``sgLineA``, ...).
    """
    unknown = set(features) - set(CONTOUR_FEATURES)
    if unknown:
        raise ValueError(f"unknown contour shader features: {sorted(unknown)}")
    f = set(features)
    two = "major" in f
    dims = "vec2" if two else "float"

    def pick(a: str, b: str) -> str:
        return f"vec2({a}, {b})" if two else a

    lines = [
        "//VTK::Light::Impl",
        "  {",
        "    // Eq. 9: the field's gradient g in field units per pixel, 1 / g at most 1e18",
        "    float sgX = sgContourField;",
        "    vec2 sgD = vec2(dFdx(sgX), dFdy(sgX));",
        "    float sgGG = dot(sgD, sgD);",
        "    float sgIG = inversesqrt(max(sgGG, 1e-36));",
        "    // the fraction of a spacing to the nearest level of each family",
        f"    {dims} sgR = (sgX - sgBase) * {pick('sgInvQ', 'sgInvMajorQ')};",
        f"    {dims} sgF = abs(sgR - floor(sgR + 0.5));",
        "    // f1 at t = frac q / g px from the line's centre: cap P(clip(a - b t, 0, 1))",
        f"    {dims} sgA = {pick('sgLineA', 'sgMajorA')};",
        f"    {dims} sgK = {pick('sgQB', 'sgMajorQB')} * sgIG;  // b px per unit fraction",
        f"    {dims} sgV = clamp(sgA - sgF * sgK, 0.0, 1.0);",
    ]
    if "beyond" in f:
        lines.append(f"    {dims} sgV2 = clamp(sgA - (1.0 - sgF) * sgK, 0.0, 1.0);")
    if "poly" in f:
        lines.append("    sgV = sgV * (sgP1 + sgV * (sgP2 + sgV * sgP3));")
        if "beyond" in f:
            lines.append("    sgV2 = sgV2 * (sgP1 + sgV2 * (sgP2 + sgV2 * sgP3));")
    if "cap" in f:
        cap = pick("sgLineCap", "sgMajorCap")
        lines.append(f"    sgV = {'min(sgV + sgV2, 1.0 / ' + cap + ')' if 'beyond' in f else 'sgV'}"
                     f" * {cap};")  # fmt: skip
    elif "beyond" in f:
        lines.append("    sgV = min(sgV + sgV2, 1.0);")
    lines.append("    // Eq. 11: fade to c_sparse where the field is flat (g < g_eps)")
    lines.append("    float sgWs = min(sgGG * sgIG * sgInvGeps, 1.0);")
    lines.append(_fade("sgV", "sgWs", "sgCSparse" if "sparse" in f else None))
    lines.append(f"    float sgInk = {'sgV.x' if two else 'sgV'};")
    if "dense" in f:
        lines.append("    // Eq. 15: minor lines closer than dense_at px fade to c_dense")
        lines.append("    float sgW = clamp(sgIG * sgDenseK1 + sgDenseK0, 0.0, 1.0);")
        lines.append(_fade("sgInk", "sgW", "sgCDense" if "cdense" in f else None))
    if two:
        lines.append("    sgInk = max(sgInk, sgV.y);  // majors never thin out")
    if "poly" in f:
        lines.append("    sgInk = clamp(sgInk, 0.0, 1.0);  // a profile may overshoot")
    lines += [
        "    gl_FragData[0].rgb = mix(gl_FragData[0].rgb, sgColor, sgInk * sgOpacity);",
        "  }",
        "",
    ]
    return "\n".join(lines)
