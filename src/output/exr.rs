//! OpenEXR output: one part with the channels compositing tools expect: `R G B A` (linear,
//! premultiplied where the background is transparent; f32, or f16 with `half`), and the layers
//! the splat mode has, always f32: `Z` (view distance in scene units, +inf where empty) and
//! `id` (the nearest point's function, -1 where empty) in closest mode, `count` (points on the
//! pixel) in average and density modes, and `N.x N.y N.z` (the shading normal in view space) in
//! closest mode with the solid look. ZIP-compressed scan lines, which every reader knows.

use std::path::Path;

use exr::prelude::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, WritableImage, f16};

use crate::output::{ImageLayers, OutputError, OutputOptions};

/// Writes `layers` to `path` as OpenEXR, atomically.
pub fn write(path: &Path, layers: &ImageLayers, options: &OutputOptions) -> Result<(), OutputError> {
    let (w, h) = (layers.width() as usize, layers.height() as usize);
    // One channel at a time, so that a large image holds one float copy of its colour at most.
    let color = |c: usize| -> FlatSamples {
        let values = layers.premultiplied_channel(c, options.transparent);
        if options.half {
            FlatSamples::F16(values.map(f16::from_f32).collect())
        } else {
            FlatSamples::F32(values.collect())
        }
    };
    let mut channels: Vec<AnyChannel<FlatSamples>> =
        ["R", "G", "B", "A"].into_iter().enumerate().map(|(c, name)| AnyChannel::new(name, color(c))).collect();
    for (name, values) in [("Z", &layers.depth), ("id", &layers.function_id), ("count", &layers.count)] {
        if let Some(v) = values {
            channels.push(AnyChannel::new(name, FlatSamples::F32(v.clone())));
        }
    }
    if let Some(normal) = &layers.normal {
        for (c, name) in ["N.x", "N.y", "N.z"].into_iter().enumerate() {
            channels.push(AnyChannel::new(name, FlatSamples::F32(normal.iter().map(|n| n[c]).collect())));
        }
    }
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels.into_iter().collect()),
    );
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer).write().to_buffered(&mut bytes).map_err(|e| OutputError::Io {
        path: path.display().to_string(),
        source: std::io::Error::other(e.to_string()),
    })?;
    let bytes = bytes.into_inner();
    crate::io::write_atomic(path, |out| out.write_all(&bytes))
        .map_err(|source| OutputError::Io { path: path.display().to_string(), source })
}

/// The channel names and size of the EXR at `path` (our own reader's view, for `--resume`
/// and tests; the independent check is `oiiotool` in tests/outputs.rs).
pub fn channels(path: &Path) -> Result<(Vec<String>, (usize, usize)), OutputError> {
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| OutputError::Invalid { path: path.display().to_string(), message: e.to_string() })?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| OutputError::Invalid { path: path.display().to_string(), message: "no image part".into() })?;
    let names = header.channels.list.iter().map(|c| c.name.to_string()).collect();
    Ok((names, (header.layer_size.0, header.layer_size.1)))
}

/// Whether `path` is an EXR of `width`×`height` whose pixels all decode.
pub fn is_complete(path: &Path, width: u32, height: u32) -> bool {
    match exr::prelude::read_all_flat_layers_from_file(path) {
        Ok(img) => {
            img.layer_data.first().is_some_and(|l| l.size == exr::prelude::Vec2(width as usize, height as usize))
        }
        Err(_) => false,
    }
}
