//! The xforms of a `<flame>` as flam3's `parse_xform_xml` and `flam3_add_symmetry` read them:
//! `<xform>` and `<finalxform>` attributes (weight, colour, colour speed or the legacy
//! `symmetry`, coefs, post, opacity, plotmode, chaos, every variation and its parameters by
//! name, the legacy `var1` / `var` lists), and `<symmetry kind>`'s rotational and dihedral
//! copies.
//!
//! Variations and parameters (with flam3's other spellings) are looked up in the variations'
//! table ([`VARIATIONS`], [`Variation::param_by_name`]), whatever it holds: a name it lacks is left out and named, with the others of its xform, in one
//! warning. As in flam3, an xform's `linear` is 0 unless the file gives it (an xform naming no
//! known variation maps every point to the origin).

use std::collections::HashMap;

use super::variations::{FLAM3_VARIATIONS, VARIATIONS};
use super::xml_source::FlameError;
use super::xml_source::{Ctx, attr_int, attr_number, numbers};
use super::{Coefs, IDENTITY, Variation, VariationTerm, Xform};

/// Largest |kind| of `<symmetry>`: each unit adds an xform.
pub const MAX_SYMMETRY_KIND: i64 = 4096;

/// `<xform>` attributes flam3 reads that change nothing in a still image.
const STILL_IGNORED: &[&str] = &["animate", "motion_frequency", "motion_function"];

/// An xform's label (Apophysis 7X, JWildfire and Fractorium name their xforms): shown nowhere,
/// changes nothing.
const LABEL: &str = "name";

/// `<xform>` attributes other programs write that are not variations and that flam3 does not
/// read (Apophysis 7X's variation colour, JWildfire's material and colour modifiers): left out
/// and named as such, not as unknown variations: once for the whole flame (`XformRead::not_read`).
const OTHER_PROGRAMS: &[&str] = &[
    "var_color",
    "material",
    "material_speed",
    "mod_gamma",
    "mod_gamma_speed",
    "mod_contrast",
    "mod_contrast_speed",
    "mod_saturation",
    "mod_saturation_speed",
    "mod_hue",
    "mod_hue_speed",
];

/// An xform read, with its xaos row as given (`None`: no `chaos` attribute).
pub(super) struct XformRead {
    pub xform: Xform,
    pub chaos: Option<Vec<f64>>,
    /// Its attributes of other programs ([`OTHER_PROGRAMS`]), for the flame's one warning.
    pub not_read: Vec<&'static str>,
}

/// One `<xform>` or `<finalxform>`. `array_len` is the number of xforms flam3 holds before
/// this one (final included): its default colour is that number's parity.
pub(super) fn xform(
    ctx: &mut Ctx,
    node: roxmltree::Node,
    is_final: bool,
    array_len: usize,
    label: &str,
) -> Result<XformRead, FlameError> {
    // Messages name the xform after the flame.
    let flame = std::mem::take(&mut ctx.flame);
    ctx.flame = format!("{flame}: {label}");
    let read = xform_in(ctx, node, is_final, array_len);
    ctx.flame = flame;
    read
}

fn xform_in(ctx: &mut Ctx, node: roxmltree::Node, is_final: bool, array_len: usize) -> Result<XformRead, FlameError> {
    let mut x = Xform {
        weight: 0.0,
        color: (array_len & 1) as f64,
        color_speed: 0.5,
        opacity: 1.0,
        coefs: IDENTITY,
        post: None,
        variation_coefs: None,
        variations: Vec::new(),
        chaos: Vec::new(),
    };
    let mut weights = vec![0.0; VARIATIONS.len()];
    let mut given: HashMap<(u8, usize), f64> = HashMap::new();
    let mut unknown: Vec<String> = Vec::new();
    let mut not_read: Vec<&'static str> = Vec::new();
    let mut chaos = None;
    let mut weight_given = false;
    // `var1` and `var` number flam3's own variations only.
    let legacy_count = FLAM3_VARIATIONS.min(VARIATIONS.len());
    for attr in node.attributes() {
        let name = attr.name();
        match name {
            "weight" => {
                weight_given = true;
                let w = attr_number(ctx, &attr)?;
                if !w.is_finite() || w < 0.0 {
                    if !is_final {
                        ctx.warn(node, format!("weight {w} is not a non-negative number; 0 is used"));
                    }
                } else {
                    x.weight = w;
                }
            }
            "symmetry" => x.color_speed = (1.0 - attr_number(ctx, &attr)?) / 2.0,
            "color_speed" => x.color_speed = attr_number(ctx, &attr)?,
            "color" => match numbers(attr.value()).as_deref() {
                // flam3 reads one number, or two (the second was a 2D colour, unused).
                Some([c] | [c, _]) => x.color = *c,
                _ => return Err(ctx.attr_error(&attr, format!("'{}' is not one or two numbers", attr.value()))),
            },
            "opacity" => x.opacity = attr_number(ctx, &attr)?,
            "plotmode" => {
                if attr.value() == "off" {
                    x.opacity = 0.0;
                }
            }
            "coefs" | "post" => {
                let v = match numbers(attr.value()) {
                    Some(v) if v.len() == 6 => v,
                    _ => return Err(ctx.attr_error(&attr, format!("expected 6 numbers, found '{}'", attr.value()))),
                };
                let mut c: Coefs = [0.0; 6];
                c.copy_from_slice(&v);
                if c.iter().any(|v| !v.is_finite()) {
                    ctx.warn(node, format!("{name} has a value that is not finite; the identity is used"));
                    c = IDENTITY;
                }
                if name == "coefs" {
                    x.coefs = c;
                } else {
                    x.post = (c != IDENTITY).then_some(c);
                }
            }
            "chaos" => {
                let row = numbers(attr.value())
                    .ok_or_else(|| ctx.attr_error(&attr, format!("'{}' is not a list of numbers", attr.value())))?;
                if is_final {
                    ctx.warn(node, "chaos ignored (the final xform is applied after every step)");
                } else {
                    chaos = Some(row);
                }
            }
            "var1" => {
                weights.iter_mut().for_each(|w| *w = 0.0);
                let j = attr_int(ctx, &attr)?;
                match usize::try_from(j).ok().filter(|&j| j < legacy_count) {
                    Some(j) => weights[j] = 1.0,
                    None => unknown.push(format!("var1=\"{j}\"")),
                }
            }
            "var" => {
                let v = numbers(attr.value())
                    .ok_or_else(|| ctx.attr_error(&attr, format!("'{}' is not a list of numbers", attr.value())))?;
                weights.iter_mut().for_each(|w| *w = 0.0);
                for (j, w) in v.into_iter().enumerate() {
                    match weights[..legacy_count].get_mut(j) {
                        Some(slot) => *slot = w,
                        None if w != 0.0 => unknown.push(format!("var[{j}]")),
                        None => {}
                    }
                }
            }
            _ if STILL_IGNORED.contains(&name) || name == LABEL => {}
            _ if let Some(known) = OTHER_PROGRAMS.iter().find(|&&known| known == name) => not_read.push(known),
            _ => {
                if let Some(v) = Variation::by_name(name) {
                    weights[v.0 as usize] = attr_number(ctx, &attr)?;
                } else if let Some((v, k)) = Variation::param_by_name(name) {
                    given.insert((v.0, k), attr_number(ctx, &attr)?);
                } else {
                    unknown.push(name.to_string());
                }
            }
        }
    }
    if is_final && weight_given && x.weight != 0.0 {
        ctx.warn(node, "weight ignored (flam3 refuses a weight on a final xform)");
    }
    if is_final {
        x.weight = 0.0;
    }
    for (j, &w) in weights.iter().enumerate() {
        if w == 0.0 {
            continue;
        }
        let info = &VARIATIONS[j];
        if !w.is_finite() {
            ctx.warn(node, format!("{} weight {w} left out", info.name));
            continue;
        }
        let params = info
            .params
            .iter()
            .enumerate()
            .map(|(k, (_, default))| given.get(&(j as u8, k)).copied().unwrap_or(*default))
            .collect();
        x.variations.push(VariationTerm { variation: Variation(j as u8), weight: w, params });
    }
    if !unknown.is_empty() {
        ctx.warn(node, format!("unknown variations or parameters, left out: {}", unknown.join(", ")));
    }
    Ok(XformRead { xform: x, chaos, not_read })
}

/// flam3's `round6`: to the nearest millionth.
fn round6(x: f64) -> f64 {
    let mut y = x * 1e6;
    if y < 0.0 {
        y -= 1.0;
    }
    1e-6 * (y + 0.5).trunc()
}

/// `<symmetry kind="k">` (flam3's `flam3_add_symmetry`): k > 1 adds k − 1 rotations by
/// 2π·i/k; k < −1 adds a reflection x → −x and the |k| − 1 rotations. The new xforms have
/// weight 1, colour speed 0, `linear` 1 and colours spread over [0, 1]; flam3 sorts them by
/// determinant (the reflection first). kind 0 (flam3 picks one at random) and 1 add nothing.
pub(super) fn symmetry(ctx: &mut Ctx, node: roxmltree::Node) -> Result<Vec<Xform>, FlameError> {
    let mut kind = 0;
    for attr in node.attributes() {
        match attr.name() {
            "kind" => kind = attr_int(ctx, &attr)?,
            other => return Err(ctx.error(node, format!("<symmetry> has an unknown attribute {other}"))),
        }
    }
    if kind == 0 {
        ctx.warn(node, "<symmetry kind=\"0\"> (flam3 picks a random symmetry) ignored");
        return Ok(Vec::new());
    }
    if kind.abs() > MAX_SYMMETRY_KIND {
        return Err(ctx.error(node, format!("<symmetry kind=\"{kind}\">: more than {MAX_SYMMETRY_KIND} copies")));
    }
    let copy = |color: f64, coefs: Coefs| Xform {
        weight: 1.0,
        color,
        color_speed: 0.0,
        opacity: 1.0,
        coefs,
        post: None,
        variation_coefs: None,
        variations: vec![VariationTerm { variation: Variation::LINEAR, weight: 1.0, params: Vec::new() }],
        chaos: Vec::new(),
    };
    let mut out = Vec::new();
    let mut sym = kind;
    if sym < 0 {
        out.push(copy(1.0, [-1.0, 0.0, 0.0, 1.0, 0.0, 0.0]));
        sym = -sym;
    }
    let angle_rad = 2.0 * std::f64::consts::PI / sym as f64;
    for k in 1..sym {
        let color = if sym < 3 { 0.0 } else { (k as f64 - 1.0) / (sym as f64 - 2.0) };
        let a = round6((k as f64 * angle_rad).cos());
        let b = round6((k as f64 * angle_rad).sin());
        out.push(copy(color, [a, b, round6(-b), a, 0.0, 0.0]));
    }
    // flam3's compare_xforms with equal colour speeds (0): by determinant a·d − b·c.
    let det = |x: &Xform| x.coefs[0] * x.coefs[3] - x.coefs[1] * x.coefs[2];
    out.sort_by(|p, q| det(p).partial_cmp(&det(q)).unwrap_or(std::cmp::Ordering::Equal));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round6_rounds_to_millionths() {
        assert_eq!(round6(0.5), 0.5);
        assert!((round6(0.123_456_7) - 0.123_457).abs() < 1e-15);
        assert!((round6(-0.123_456_7) + 0.123_457).abs() < 1e-15);
        assert_eq!(round6(6.123e-17), 0.0);
    }
}
