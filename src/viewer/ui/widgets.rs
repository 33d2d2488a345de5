//! Widgets the panels share, below every `*_ui` file so that none of them imports another.

/// A slider that never writes the state's value back: with egui's default clamping
/// (`SliderClamping::Always`) a slider re-clamps and re-rounds the value it shows every frame
/// and reports that as a change, which turned a value outside the range (or with more decimals
/// than shown) into an edit every frame.
pub fn slider<'a, Num: egui::emath::Numeric>(
    value: &'a mut Num,
    range: std::ops::RangeInclusive<Num>,
) -> egui::Slider<'a> {
    egui::Slider::new(value, range).clamping(egui::SliderClamping::Edits)
}
