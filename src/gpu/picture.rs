//! The live view's drawing on an adapter without compute shaders (a browser's WebGL2, where
//! wgpu has neither compute passes nor storage buffers): the accumulation stays on the CPU (the
//! live view's CPU route fills it), the resolve's CPU twin (`crate::resolve`, the density
//! estimate's where one applies) resolves it into an 8-bit picture, and `shaders/picture.wgsl`
//! draws that as a texture into the accumulation's rectangle of the target.
//! [`super::progressive::Progressive`] keeps its bookkeeping (clears, convergence, estimates,
//! rest) the same over both drawings; this one resolves again only when its inputs or the
//! resolve's arguments changed.
//!
//! [`PictureDraw`], the drawing of such a picture, also draws the density estimate's picture
//! that the GPU resolves once per estimate (`super::density_estimation`).

use rayon::prelude::*;

use crate::resolve::density_estimation::Estimated;
use crate::resolve::{
    LightRows as LightCache, ResolveArgs, ResolveInputs, ResolveParams, max_count, resolve_row, resolve_row_cached,
};
use crate::scene::spec::SplatMode;

use super::GpuContext;
use super::resolve::LightRows;

/// Mirrors `struct Placement` in `shaders/picture.wgsl`: keep in sync.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Placement {
    /// The target pixel of the picture's pixel (0, 0).
    pub origin: [u32; 2],
    pub pad: [u32; 2],
}

/// A picture's texture, of the accumulation's size ([`PictureDraw::texture`]).
pub struct PictureTexture {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub size_px: [u32; 2],
    /// The texture is sRGB (as the target is: it decodes what the target encodes again) or
    /// plain (WebGL2 has no views of another format).
    pub srgb: bool,
    bind_group: wgpu::BindGroup,
}

impl PictureTexture {
    /// The texture's format: 8-bit RGBA, sRGB or plain.
    pub fn format(&self) -> wgpu::TextureFormat {
        picture_format(self.srgb)
    }
}

fn picture_format(srgb: bool) -> wgpu::TextureFormat {
    if srgb { wgpu::TextureFormat::Rgba8UnormSrgb } else { wgpu::TextureFormat::Rgba8Unorm }
}

/// Draws a picture of the accumulation's size into the accumulation's rectangle of a target
/// (`shaders/picture.wgsl`, a texel a pixel), the rest of the target cleared to black, as the
/// resolve draws.
pub struct PictureDraw {
    module: wgpu::ShaderModule,
    layout: wgpu::BindGroupLayout,
    pipelines: Vec<(wgpu::TextureFormat, wgpu::RenderPipeline)>,
    placement: wgpu::Buffer,
}

impl PictureDraw {
    pub fn new(device: &wgpu::Device) -> Self {
        Self {
            module: super::shaders::module(device, "picture"),
            layout: bind_group_layout(device),
            pipelines: Vec::new(),
            placement: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("picture_placement"),
                size: std::mem::size_of::<Placement>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }

    /// A texture for a picture of `size_px`, sRGB for a target that is, with `usage` beside
    /// TEXTURE_BINDING and RENDER_ATTACHMENT (COPY_DST for a picture uploaded).
    fn texture(&self, ctx: &GpuContext, size_px: [u32; 2], srgb: bool, usage: wgpu::TextureUsages) -> PictureTexture {
        let format = picture_format(srgb);
        let usage = wgpu::TextureUsages::TEXTURE_BINDING | usage;
        let texture = super::readback::offscreen_texture(ctx, "picture", size_px[0], size_px[1], format, usage);
        let view = texture.create_view(&Default::default());
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("picture"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                wgpu::BindGroupEntry { binding: 1, resource: self.placement.as_entire_binding() },
            ],
        });
        PictureTexture { texture, view, size_px, srgb, bind_group }
    }

    /// Makes `texture` anew (as [`Self::texture`]) where there is none or it is not of
    /// `size_px` and the sRGB-ness `srgb`; true when it did (its picture is to be made again).
    pub fn fit(
        &self,
        ctx: &GpuContext,
        texture: &mut Option<PictureTexture>,
        size_px: [u32; 2],
        srgb: bool,
        usage: wgpu::TextureUsages,
    ) -> bool {
        let anew = texture.as_ref().is_none_or(|t| t.size_px != size_px || t.srgb != srgb);
        if anew {
            *texture = Some(self.texture(ctx, size_px, srgb, usage));
        }
        anew
    }

    /// Records the draw of `picture` onto `target` of `format`, its pixel (0, 0) at
    /// `origin_px` (one draw per encoder: the placement is written before the submission).
    pub fn draw(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        picture: &PictureTexture,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
        origin_px: [u32; 2],
    ) {
        let placement = Placement { origin: origin_px, pad: [0; 2] };
        ctx.queue.write_buffer(&self.placement, 0, bytemuck::bytes_of(&placement));
        let pipeline = self.pipeline(&ctx.device, format);
        let mut pass = super::resolve::resolve_pass(encoder, "picture", target, origin_px, picture.size_px);
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &picture.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// The pipeline drawing onto `format` targets.
    fn pipeline(&mut self, device: &wgpu::Device, format: wgpu::TextureFormat) -> &wgpu::RenderPipeline {
        let index = match self.pipelines.iter().position(|(f, _)| *f == format) {
            Some(i) => i,
            None => {
                let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some("picture"),
                    bind_group_layouts: &[Some(&self.layout)],
                    immediate_size: 0,
                });
                let pipeline = super::resolve::fullscreen_pipeline_in(
                    device,
                    Some(&layout),
                    &self.module,
                    "picture_fragment",
                    &[],
                    format,
                );
                self.pipelines.push((format, pipeline));
                self.pipelines.len() - 1
            }
        };
        &self.pipelines[index].1
    }
}

pub struct CpuPicture {
    /// The accumulation as last handed over ([`Self::set_accum`]), in the GPU's layout.
    accum: Vec<u32>,
    /// The shadow map's keys as last handed over (empty without one).
    shadow: Vec<u32>,
    /// The function colours (linear RGB), from the IFS.
    colors: Vec<[f32; 3]>,
    /// The density estimate the draws show while [`Self::draw`] is told to.
    estimate: Option<Estimated>,
    /// The inputs changed since the picture was last resolved.
    stale: bool,
    /// What the picture was last resolved with (the parameters, and whether from the estimate).
    shown: Option<(ResolveParams, bool)>,
    /// The picture, RGBA8 rows of the accumulation's width.
    rgba: Vec<u8>,
    /// The 8-bit sRGB encode without a `powf` a channel (most pixels are background).
    srgb8: crate::color::Srgb8Table,
    /// The solid look's light of every pixel, refreshed in bands as the GPU's light cache is
    /// ([`LightRows::Refresh`]).
    light: Option<LightCache>,
    drawing: PictureDraw,
    texture: Option<PictureTexture>,
}

impl CpuPicture {
    pub fn new(device: &wgpu::Device) -> Self {
        Self {
            accum: Vec::new(),
            shadow: Vec::new(),
            colors: Vec::new(),
            estimate: None,
            stale: true,
            shown: None,
            rgba: Vec::new(),
            srgb8: crate::color::Srgb8Table::new(),
            light: None,
            drawing: PictureDraw::new(device),
            texture: None,
        }
    }

    /// The function colours of a new IFS.
    pub fn set_colors(&mut self, colors: &[[f32; 3]]) {
        self.colors = colors.to_vec();
        self.stale = true;
    }

    /// The whole accumulation since the last clear (as the GPU's accumulation buffer holds it).
    pub fn set_accum(&mut self, accum: &[u32]) {
        self.accum.clear();
        self.accum.extend_from_slice(accum);
        self.stale = true;
    }

    /// The shadow map's keys of the frame handed over next.
    pub fn set_shadow(&mut self, shadow: &[u32]) {
        self.shadow.clear();
        self.shadow.extend_from_slice(shadow);
        self.stale = true;
    }

    /// Empties the accumulation (nothing splatted yet: the background).
    pub fn clear(&mut self) {
        self.accum.clear();
        self.stale = true;
    }

    /// The accumulation as last handed over.
    pub fn accum(&self) -> &[u32] {
        &self.accum
    }

    /// Takes `e` as the estimate the draws show when told to.
    pub fn set_estimate(&mut self, e: Estimated) {
        self.estimate = Some(e);
        self.stale = true;
    }

    /// Resolves the accumulation (or the estimate, with `estimated`) with `args` for a
    /// `width`×`height` accumulation, the solid look's light computed per pixel or read from
    /// the light cache after refreshing its rows `light` (as the GPU's resolve does), unless the
    /// picture already shows it; records its draw onto `target` at `args.origin_px`.
    #[expect(clippy::too_many_arguments, reason = "the draw's inputs, each a different kind")]
    pub fn draw(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        args: &ResolveArgs,
        (width, height): (u32, u32),
        estimated: bool,
        light: LightRows,
        target: &wgpu::TextureView,
        format: wgpu::TextureFormat,
    ) {
        // The picture holds sRGB-encoded bytes whatever the target (an sRGB target decodes and
        // encodes them again): the resolve's linear colours, encoded here by a table.
        let params = ResolveArgs { origin_px: [0, 0], ..*args }.params(width, height, false);
        // A refreshed band changes the picture even where the accumulation did not.
        let refresh = matches!(light, LightRows::Refresh { start, end } if start < end);
        if self.stale || refresh || self.shown != Some((params, estimated)) {
            self.resolve(&params, args.mode, estimated, light);
            self.stale = false;
            self.shown = Some((params, estimated));
            self.upload(ctx, [width, height], format.is_srgb());
        }
        if let Some(texture) = &self.texture {
            self.drawing.draw(ctx, encoder, texture, target, format, args.origin_px);
        }
    }

    /// Resolves into `self.rgba` with `p` (linear colours, of the accumulation's size) on the
    /// CPU, 8-bit sRGB as the resolve writes into a unorm target: the background where nothing
    /// is splatted yet.
    fn resolve(&mut self, p: &ResolveParams, mode: SplatMode, estimated: bool, light: LightRows) {
        let (w, h) = (p.width as usize, p.height as usize);
        self.rgba.resize(4 * w * h, 255);
        let rows = self.rgba.par_chunks_mut((4 * w).max(1)).enumerate();
        let srgb8 = &self.srgb8;
        let encode = |c: [f32; 3]| {
            let [r, g, b] = c.map(|v| srgb8.encode(v));
            [r, g, b, 255]
        };
        // Most pixels show the background, encoded once.
        let background = [p.background[0], p.background[1], p.background[2]];
        let background_bytes = encode(background);
        let rgba = |c: [f32; 3]| if c == background { background_bytes } else { encode(c) };
        if let Some(e) = self.estimate.as_ref().filter(|e| estimated && (e.width, e.height) == (p.width, p.height)) {
            rows.for_each(|(y, row)| {
                for (x, px) in row.chunks_exact_mut(4).enumerate() {
                    px.copy_from_slice(&rgba(e.fragment(p, x as u32, y as u32)));
                }
            });
            return;
        }
        let words = if mode == SplatMode::Closest { w * h } else { 4 * w * h };
        if self.accum.len() != words {
            rows.for_each(|(_, row)| row.chunks_exact_mut(4).for_each(|px| px.copy_from_slice(&background_bytes)));
            return;
        }
        let mut p = *p;
        // The shadow map must be the view's (as on the GPU, where the chaos game sizes it).
        let texels = p.shadow_side_px as usize * p.shadow_side_px as usize;
        if self.shadow.len() != texels || texels == 0 {
            p.shadows = 0.0;
        }
        let inputs = ResolveInputs {
            accum: &self.accum,
            colors: &self.colors,
            max_count: if mode == SplatMode::Density { max_count(&self.accum, w * h) } else { 0 },
            shadow: &self.shadow,
        };
        if inputs.colors.is_empty() {
            return;
        }
        let lit = mode == SplatMode::Closest && (p.shading > 0.0 || p.occlusion > 0.0);
        match light {
            LightRows::Refresh { start, end } if lit => {
                let cache = match self.light.take() {
                    Some(cache) if cache.covers(p.width, p.height) => self.light.insert(cache),
                    _ => self.light.insert(LightCache::whole(&p)),
                };
                if start < end {
                    cache.refresh(&p, &inputs, start as i32..=end as i32 - 1);
                }
                let cache = &*cache;
                rows.for_each(|(y, row)| {
                    resolve_row_cached(&p, &inputs, y as u32, cache, |x, c| {
                        row[4 * x..4 * x + 4].copy_from_slice(&rgba(c))
                    })
                });
            }
            _ => rows.for_each(|(y, row)| {
                resolve_row(&p, &inputs, y as u32, |x, c| row[4 * x..4 * x + 4].copy_from_slice(&rgba(c)))
            }),
        }
    }

    /// Writes the picture into the texture, made anew when the size or the target's kind changed.
    fn upload(&mut self, ctx: &GpuContext, size_px: [u32; 2], srgb: bool) {
        self.drawing.fit(ctx, &mut self.texture, size_px, srgb, wgpu::TextureUsages::COPY_DST);
        let Some(t) = &self.texture else { return };
        ctx.queue.write_texture(
            t.texture.as_image_copy(),
            &self.rgba,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * size_px[0]), rows_per_image: None },
            wgpu::Extent3d { width: size_px[0], height: size_px[1], depth_or_array_layers: 1 },
        );
    }
}

/// The bind group layout of `shaders/picture.wgsl`: the picture and its placement.
fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("picture"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ],
    })
}
