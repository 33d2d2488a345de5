//! A `kind = "flame"` function's fields, checked (and a key's override of them): `coefs`,
//! `post` and `variation_coefs` as flam3's six numbers, `variations` (weight by flam3's variation name), `params`
//! (flam3's attribute names, `julian_power`; every parameter belongs to a variation the function
//! uses, the ones left out take flam3's defaults), `color_speed` and `opacity` in 0..1. An unknown
//! variation or parameter is named in the error, with its line and column.

use std::ops::Range;

use toml::Spanned;

use crate::flame::{Coefs, Variation, VariationTerm};
use crate::scene::file::{FlameFields, NamedNumbers};
use crate::scene::spec::FlameDef;

use super::{Checker, Res};

/// The names of the fields of a flame function.
pub(super) const FLAME_FIELDS: [&str; 7] =
    ["coefs", "post", "variation_coefs", "variations", "params", "color_speed", "opacity"];

impl Checker<'_> {
    /// A flame function's definition from its fields (`base` None), or a key's override of
    /// `base` (each field present replaces the base's numbers; the variations and the
    /// post-affine stay the base's). `prefix` is the function's field path (`function[2]`).
    pub(super) fn flame_def(
        &self,
        prefix: &str,
        span: Range<usize>,
        f: FlameFields<'_>,
        base: Option<&FlameDef>,
    ) -> Res<FlameDef> {
        let field = |name: &str| format!("{prefix}.{name}");
        let coefs = match (f.coefs, base) {
            (Some(c), _) => self.coefs(c, &field("coefs"))?,
            (None, Some(b)) => b.coefs,
            (None, None) => {
                return Err(self.err(span, &field("coefs"), "a `flame` function needs `coefs` (flam3's a b c d e f)"));
            }
        };
        let post = match (f.post, base) {
            (Some(p), Some(b)) if b.post.is_none() => {
                return Err(self.err(
                    p.span(),
                    &field("post"),
                    "the function has no post-affine; a key may change only numbers it has",
                ));
            }
            (Some(p), _) => Some(self.coefs(p, &field("post"))?),
            (None, Some(b)) => b.post,
            (None, None) => None,
        };
        let variation_coefs = match (f.variation_coefs, base) {
            (Some(c), Some(b)) if b.variation_coefs.is_none() => {
                return Err(self.err(
                    c.span(),
                    &field("variation_coefs"),
                    "the function has no variation_coefs; a key may change only numbers it has",
                ));
            }
            (Some(c), _) => Some(self.coefs(c, &field("variation_coefs"))?),
            (None, Some(b)) => b.variation_coefs,
            (None, None) => None,
        };
        let mut variations = match (f.variations, base) {
            (Some(v), None) => self.variations(v, &field("variations"))?,
            (Some(v), Some(b)) => self.variation_weights(v, &field("variations"), &b.variations)?,
            (None, Some(b)) => b.variations.clone(),
            (None, None) => {
                return Err(self.err(
                    span,
                    &field("variations"),
                    "a `flame` function needs `variations`, weights by flam3's names (`{ linear = 1.0 }`)",
                ));
            }
        };
        if let Some(p) = f.params {
            self.params(p, &field("params"), &mut variations)?;
        }
        let color_speed = match (f.color_speed, base) {
            (Some(s), _) => self.in_range(s, &field("color_speed"), 0.0, 1.0)?,
            (None, Some(b)) => b.color_speed,
            (None, None) => FlameDef::DEFAULT_COLOR_SPEED,
        };
        let opacity = match (f.opacity, base) {
            (Some(o), _) => self.in_range(o, &field("opacity"), 0.0, 1.0)?,
            (None, Some(b)) => b.opacity,
            (None, None) => FlameDef::DEFAULT_OPACITY,
        };
        Ok(FlameDef { coefs, post, variation_coefs, variations, color_speed, opacity })
    }

    fn coefs(&self, c: &Spanned<Vec<f64>>, field: &str) -> Res<Coefs> {
        let v = c.get_ref();
        if v.len() != 6 {
            return Err(self.err(
                c.span(),
                field,
                format!(
                    "expected flam3's 6 numbers a b c d e f (x' = a·x + c·y + e, y' = b·x + d·y + f), found {}",
                    v.len()
                ),
            ));
        }
        self.coordinates(c.span(), v, field)?;
        Ok(std::array::from_fn(|k| v[k]))
    }

    /// A finite weight or parameter of magnitude at most the scene's coordinate limit
    /// (`spec::MAX_COORDINATE`).
    fn flame_number(&self, v: &Spanned<f64>, field: &str) -> Res<f64> {
        self.coordinates(v.span(), &[*v.get_ref()], field)?;
        Ok(*v.get_ref())
    }

    /// A function's variations: each name one of flam3's, its parameters at their defaults, in
    /// flam3's order.
    fn variations(&self, v: &NamedNumbers, field: &str) -> Res<Vec<VariationTerm>> {
        if v.get_ref().is_empty() {
            return Err(self.err(v.span(), field, "lists no variation; give at least one weight (`linear = 1.0`)"));
        }
        let mut out = Vec::new();
        for (name, weight) in v.get_ref() {
            let at = format!("{field}.{}", name.get_ref());
            let variation = Variation::by_name(name.get_ref()).ok_or_else(|| {
                self.err(
                    name.span(),
                    &at,
                    format!("`{}` is not one of flam3's variations (linear, spherical, julia, …)", name.get_ref()),
                )
            })?;
            let weight = self.flame_number(weight, &at)?;
            out.push(VariationTerm { variation, weight, params: variation.default_params() });
        }
        out.sort_by_key(|t| t.variation.0);
        Ok(out)
    }

    /// A key's weights: each names a variation of the function.
    fn variation_weights(&self, v: &NamedNumbers, field: &str, base: &[VariationTerm]) -> Res<Vec<VariationTerm>> {
        let mut out = base.to_vec();
        for (name, weight) in v.get_ref() {
            let at = format!("{field}.{}", name.get_ref());
            let Some(t) = out.iter_mut().find(|t| t.variation.name() == name.get_ref()) else {
                let uses = base.iter().map(|t| t.variation.name()).collect::<Vec<_>>().join(", ");
                return Err(self.err(
                    name.span(),
                    &at,
                    format!(
                        "the function does not use `{}` (it uses {uses}); a key may change only numbers",
                        name.get_ref()
                    ),
                ));
            };
            t.weight = self.flame_number(weight, &at)?;
        }
        Ok(out)
    }

    /// Sets the parameters `p` names in `variations`.
    fn params(&self, p: &NamedNumbers, field: &str, variations: &mut [VariationTerm]) -> Res<()> {
        for (name, value) in p.get_ref() {
            let at = format!("{field}.{}", name.get_ref());
            let (variation, index) = Variation::param_by_name(name.get_ref()).ok_or_else(|| {
                self.err(
                    name.span(),
                    &at,
                    format!("`{}` is not a parameter of any of flam3's variations (julian_power, …)", name.get_ref()),
                )
            })?;
            let Some(t) = variations.iter_mut().find(|t| t.variation == variation) else {
                return Err(self.err(
                    name.span(),
                    &at,
                    format!(
                        "`{}` is a parameter of `{}`, which the function does not use (add it to `variations`)",
                        name.get_ref(),
                        variation.name()
                    ),
                ));
            };
            t.params[index] = self.flame_number(value, &at)?;
        }
        Ok(())
    }
}
