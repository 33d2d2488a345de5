#!/usr/bin/env python3
"""Writes scenes/{tapering,twisting,fantasy,plant1,plant2}.toml from the paper's appendix tables
(../shared/paper/appendix_tables.json), applying the corrections documented in each file."""
import json, sys, pathlib

src = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "../shared/paper/appendix_tables.json")
tables = json.loads(src.read_text())["ifs"]

META = {
    "tapering": ("Tapering of the Sierpinski tetrahedron (paper table 1, plates 1 and 2).", 0.55, 1,
                 [("functions[0] point 12", "x 36.66 -> 36.67: every other table entry is symmetric about x = 25 "
                   "(43.33 / 6.67, 30 / 20, and point 13 of the same layer reads 36.67); a rounding slip.",
                   lambda t: t["functions"][0][12].__setitem__(0, 36.67))]),
    "twisting": ("Twisting of the Sierpinski tetrahedron (paper table 2, plate 3).", 0.69, 3,
                 [("f2 point 13, f3 point 2", "y 8.333 / -8.333 -> 8.33 / -8.33, the value of every other point "
                   "of that grid layer (a printing inconsistency; no effect on figure 8).",
                   lambda t: (t["functions"][1][13].__setitem__(1, 8.33), t["functions"][2][2].__setitem__(1, -8.33)))]),
    "fantasy": ("Tapering of a grid: a strange nonlinear IFS with five functions (paper table 3, plate 4).", 0.64, 4, []),
    "plant1": ("Linear plant modeling: five linear functions given as grid distortions (paper table 5, plates 5 and 6).", 0.50, 6,
               [("initial grid z", "z = ±23.37 -> ±46.74. As printed, the initial grid is 46.74 deep while every "
                 "transformed edge has length 40, which gives contractivity 40/46.74 = 0.86 (figure 8 says 0.50) "
                 "and puts f4 and f5 points at z = ±46.74 outside the grid (violating containment). With z = ±46.74 "
                 "(exactly twice the printed value; 23.37 is plant 2's half-depth, copied by mistake) every edge "
                 "ratio is at most 40/80 = 0.50, as figure 8 states, and all points are contained.",
                 lambda t: [p.__setitem__(2, 2 * p[2]) for p in t["initial"]])]),
    "plant2": ("Nonlinear plant modeling (paper table 4, plates 7 and 8).", 0.68, 8,
               [("initial grid x", "x = ±21.20 -> ±21.21. f3 maps to x = -21.21 (15·√2 = 21.213 rounded), 0.01 "
                 "outside the printed grid; the grid's half-width is the same 15·√2 rounded up, so containment "
                 "holds. Figure 8's 0.68 is unchanged (0.678).",
                 lambda t: [p.__setitem__(0, 21.21 if p[0] > 0 else -21.21) for p in t["initial"]])]),
}
COLORS = ["#f26d4f", "#4fb3f2", "#8ce05a", "#f2c94c", "#c07cf2"]

def fmt(x):
    s = f"{x:.3f}".rstrip("0").rstrip(".")
    return s if s not in ("-0",) else "0"

for name, t in tables.items():
    desc, fig8, plate, fixes = META[name]
    for _, _, fix in fixes:
        fix(t)
    nx, ny, nz = t["dims"]
    init = t["initial"]
    axes = [sorted({p[a] for p in init}) for a in range(3)]
    # The layout (x outermost, z fastest) must reproduce the initial points exactly.
    rebuilt = [[axes[0][i], axes[1][j], axes[2][k]] for i in range(nx) for j in range(ny) for k in range(nz)]
    assert rebuilt == init, name
    out = [f"# {desc}",
           f"# Figure 8: {len(t['functions'])} functions, grid {nx}x{ny}x{nz}, contractivity {fig8:.2f}.",
           "# Points are listed as in the paper's table: x outermost, z fastest."]
    if fixes:
        out.append("#")
        out.append("# Corrections to the table as printed (see README, 'Paper scenes'):")
        for where, why, _ in fixes:
            words = f"- {where}: {why}".split()
            line = "#"
            for w in words:
                if len(line) + len(w) + 1 > 98:
                    out.append(line)
                    line = "#  "
                line += " " + w
            out.append(line)
    out += ["", "version = 1", f'name = "{name}"', f'description = "{desc}"', "",
            "[grid]"] + [f"{c} = [{', '.join(fmt(v) for v in axes[a])}]" for a, c in enumerate("xyz")] + [""]
    for fi, f in enumerate(t["functions"]):
        out += ["[[function]]", f'name = "f{fi + 1}"', 'kind = "grid"', f'color = "{COLORS[fi % len(COLORS)]}"', "points = ["]
        out += [f"  [{', '.join(fmt(v) for v in p)}]," for p in f]
        out += ["]", ""]
    out += ["[render]", "width = 960", "height = 720", "points = 4_000_000", 'mode = "closest"', "depth_cue = 0.75", ""]
    pathlib.Path(f"scenes/{name}.toml").write_text("\n".join(out))
    print("wrote", name)
