//! Checks the depth-of-field fields of `[render]` and `[key.render]` (`crate::splat::lens`):
//! `aperture` a finite number ≥ 0 (scene units), `focus_distance` a finite number > 0.

use toml::Spanned;

use super::{Checker, Res};

impl Checker<'_> {
    /// The aperture and focus distance of a `section` (`render`, `key[2].render`), each if set.
    pub(super) fn lens(
        &self,
        aperture: &Option<Spanned<f64>>,
        focus_distance: &Option<Spanned<f64>>,
        section: &str,
    ) -> Res<(Option<f32>, Option<f32>)> {
        let aperture = match aperture {
            Some(a) => {
                let field = format!("{section}.aperture");
                let v = self.finite(a, &field)?;
                if !(v >= 0.0 && v <= f32::MAX as f64) {
                    return Err(self.err(
                        a.span(),
                        &field,
                        format!("must be 0 (no depth of field) or more, found {v}"),
                    ));
                }
                Some(v as f32)
            }
            None => None,
        };
        let focus_distance = match focus_distance {
            Some(f) => {
                let field = format!("{section}.focus_distance");
                let v = self.finite(f, &field)?;
                // Positive also in f32 (1/f is the lens's focus term).
                if !(v as f32 > 0.0 && v <= f32::MAX as f64) {
                    return Err(self.err(
                        f.span(),
                        &field,
                        format!("must be a distance from the eye greater than 0, found {v}"),
                    ));
                }
                Some(v as f32)
            }
            None => None,
        };
        Ok((aperture, focus_distance))
    }
}
