//! One shot: everything a render of a scene at one time needs before the chaos game runs,
//! prepared in one place. Scene at t → IFS → compiled tables → attractor bounds → camera →
//! splat view → chunk plan and random streams. The CPU render, the GPU render, the recorder,
//! the benches and `export points` all start from a [`Shot`], so a still, a frame of an
//! animation and an exported point set of the same scene, time and seed agree by construction.
//!
//! Two choices differ between outputs and are arguments: the bounds (a still takes the
//! attractor's own; a recording takes bounds fixed over the whole timeline, so the depth cue
//! does not breathe) and the [`Framing`] of the camera.

use glam::{DVec3, Vec3};

use crate::camera::OrbitCamera;
use crate::chaos_game::{self, ChunkPlan, CompiledIfs, PlanError, PointSink};
use crate::model::Ifs;
use crate::palette::{self, Palette};
use crate::resolve::ResolveStyle;
use crate::scene::Scene;
use crate::scene::spec::{ColorMode, RenderSettings};
use crate::splat::{Framebuffer, Lens, SharedFramebuffer, SplatView};

#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ShotError {
    #[error("the scene has no enabled function at t = {t_secs} s")]
    NoFunctions { t_secs: f64 },
    #[error(transparent)]
    Points(#[from] PlanError),
    #[error(transparent)]
    Lens(#[from] crate::splat::lens::LensError),
}

/// `compiled` (of `scene`'s functions) coloured as `settings.color` says: unchanged for
/// function colour; for palette colour each compiled function gets its scene function's
/// `palette_index` (default i / (n − 1) over all the scene's functions, so that disabling one
/// keeps the others' colours) and the colour table becomes the palette. The table is in the
/// space the colours are mixed in ([`RenderSettings::blend`]).
pub fn with_color_mode(compiled: CompiledIfs, scene: &Scene, settings: &RenderSettings) -> CompiledIfs {
    let mut compiled = colored(compiled, scene, settings);
    let blend = settings.blend();
    for c in &mut compiled.colors {
        *c = blend.of_linear(*c);
    }
    compiled
}

/// `compiled`'s colour table (linear) as `settings.color` says.
fn colored(compiled: CompiledIfs, scene: &Scene, settings: &RenderSettings) -> CompiledIfs {
    if settings.color != ColorMode::Palette {
        return compiled;
    }
    let n = scene.functions.len();
    let coords = compiled
        .source_index
        .iter()
        .map(|&i| scene.functions.get(i).and_then(|f| f.palette_index).unwrap_or(palette::default_index(i, n)) as f32)
        .collect();
    let fallback;
    let palette = match &settings.palette {
        Some(p) => p,
        None => {
            fallback = Palette::builtin(palette::DEFAULT).expect("the default palette is built in");
            &fallback
        }
    };
    let mut compiled = compiled.with_palette(coords, palette);
    compiled.palette_linear = settings.palette_mode == crate::flame::PaletteMode::Linear;
    compiled
}

/// The seed of the short runs that give a shot its bounds and its framing sample: fixed, not the
/// render's seed, so that renders of one scene with other seeds or point counts frame it (and
/// span its depth cue) alike, pixel for pixel. 7 is the seed the golden images
/// (`tests/cpu_golden.rs`) are rendered with, so they keep the bytes they had when the bounds
/// were drawn from the render's seed.
pub const FRAMING_SEED: u32 = 7;

/// How a shot's camera is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Framing {
    /// The scene's camera at t, its open fields filled from the bounds, and where the scene
    /// leaves both target and distance open, fitted to a sample of the attractor ([`frame_camera`]):
    /// what a still render does.
    Fit,
    /// The scene's camera at t, its open fields filled from the bounds (no fit to points): what
    /// the recorder and the benches do.
    Scene,
    /// This camera.
    Given(OrbitCamera),
}

/// A scene at one time, ready for the chaos game: see the module comment.
#[derive(Clone, Debug)]
pub struct Shot {
    pub t_secs: f64,
    /// Image size, point count, seed and splat settings.
    pub settings: RenderSettings,
    pub ifs: Ifs,
    pub compiled: CompiledIfs,
    /// The box the camera is framed on and the depth cue spans.
    pub bounds: (DVec3, DVec3),
    pub camera: OrbitCamera,
    pub view: SplatView,
    /// The chunks of `settings.points`.
    pub plan: ChunkPlan,
    /// The random streams' frame (the chaos game's `frame` argument): 0 for a still; a recording
    /// gives every temporal sample of every frame its own.
    pub stream: u32,
    /// How the accumulation is drawn (shading, point radius).
    pub style: ResolveStyle,
}

impl Shot {
    /// Prepares `scene` at `t_secs` with `settings`: `bounds` overrides the attractor's bounds
    /// (estimated from a short run seeded with [`FRAMING_SEED`] when None); the stream is 0 and
    /// the style the plain resolve (see [`Self::with_stream`], [`Self::style`]).
    pub fn prepare(
        scene: &Scene,
        t_secs: f64,
        settings: &RenderSettings,
        framing: Framing,
        bounds: Option<(DVec3, DVec3)>,
    ) -> Result<Self, ShotError> {
        let ifs = scene.at(t_secs);
        let compiled = CompiledIfs::new(&ifs).ok_or(ShotError::NoFunctions { t_secs })?;
        let compiled = with_color_mode(compiled, scene, settings);
        let plan = ChunkPlan::new(settings.points)?;
        let bounds = bounds.unwrap_or_else(|| chaos_game::attractor_bounds(&compiled, FRAMING_SEED));
        let camera = match framing {
            Framing::Given(camera) => camera,
            Framing::Scene => scene.camera_for_at(t_secs, bounds),
            Framing::Fit => {
                let sample = chaos_game::attractor_sample(&compiled, FRAMING_SEED);
                frame_camera(scene, t_secs, bounds, &sample, settings.width as f32 / settings.height as f32)
            }
        };
        let view = SplatView::new(
            &camera,
            settings.width,
            settings.height,
            bounds,
            settings.mode,
            settings.depth_cue,
            settings.blend().of_linear(settings.background),
        )
        .with_lens(lens_of(&camera, settings)?);
        let style = ResolveStyle::of(settings, scene.domain.dimension());
        let view = with_shadow_of(view, &style, &camera, bounds);
        Ok(Self { t_secs, settings: settings.clone(), ifs, compiled, bounds, camera, view, plan, stream: 0, style })
    }

    /// The shot drawing from the random streams of frame `stream`.
    pub fn with_stream(self, stream: u32) -> Self {
        Self { stream, ..self }
    }

    /// The shot drawn with `style` (with a shadow map where it casts shadows).
    pub fn with_style(self, style: ResolveStyle) -> Self {
        let view = with_shadow_of(SplatView { shadow: None, ..self.view }, &style, &self.camera, self.bounds);
        Self { style, view, ..self }
    }

    /// Runs the shot's chaos game in parallel (see [`chaos_game::run_parallel`]); `progress`
    /// is called once per finished chunk.
    pub fn run<S: PointSink + Send>(
        &self,
        make_sink: impl Fn() -> S + Sync,
        merge: impl Fn(S, S) -> S + Sync + Send,
        progress: impl Fn() + Sync,
    ) -> S {
        chaos_game::run_parallel(
            &self.compiled,
            self.settings.seed,
            self.stream,
            &self.plan,
            make_sink,
            merge,
            progress,
        )
    }

    /// Runs the shot's chaos game into its splat view, in the way [`Accumulation::for_view`]
    /// picks for the current thread count.
    pub fn splat(&self, progress: impl Fn() + Sync) -> Framebuffer {
        self.splat_chunks(0..self.plan.chunks(), Accumulation::for_view(&self.view), progress)
    }

    /// Runs chunks `chunks` of the shot's chaos game into its splat view with `accumulation`.
    /// Every way gives the same framebuffer (the updates are order-independent).
    pub fn splat_chunks(
        &self,
        chunks: std::ops::Range<u32>,
        accumulation: Accumulation,
        progress: impl Fn() + Sync,
    ) -> Framebuffer {
        let (ifs, seed, frame, plan) = (&self.compiled, self.settings.seed, self.stream, &self.plan);
        let points_drawn = plan.splats_of(chunks.clone());
        let mut framebuffer = match accumulation {
            Accumulation::PerThread => {
                let several = rayon::current_num_threads() > 1;
                let make = || {
                    let mut framebuffer = Framebuffer::new(self.view, self.compiled.colors.clone());
                    if several {
                        framebuffer.touch_pages();
                    }
                    framebuffer
                };
                chaos_game::run_per_thread(ifs, seed, frame, plan, chunks, make, progress)
                    .into_iter()
                    .reduce(Framebuffer::merge)
                    .unwrap_or_else(|| Framebuffer::new(self.view, self.compiled.colors.clone()))
            }
            Accumulation::Shared => {
                let mut shared = SharedFramebuffer::new(self.view, self.compiled.colors.clone());
                let threads = rayon::current_num_threads();
                shared.splat_with(threads, |target| {
                    // Each writer flushes when it is dropped, inside `run_per_thread`'s return
                    // value, so every update is in before `splat_with` returns.
                    drop(chaos_game::run_per_thread(ifs, seed, frame, plan, chunks, || target.writer(), progress));
                });
                shared.into_framebuffer()
            }
        };
        framebuffer.points_drawn = points_drawn;
        framebuffer
    }
}

/// `view` with the shadow map that `style` needs (none where it casts no shadows).
fn with_shadow_of(view: SplatView, style: &ResolveStyle, camera: &OrbitCamera, bounds: (DVec3, DVec3)) -> SplatView {
    if style.casts_shadows(view.mode) { view.with_shadow(camera, bounds, style.key_light()) } else { view }
}

/// The depth-of-field lens of `settings` (aperture, focus distance, seed) for `camera`.
pub fn lens_of(camera: &OrbitCamera, settings: &RenderSettings) -> Result<Lens, crate::splat::lens::LensError> {
    Lens::new(camera, settings.height, settings.aperture, settings.focus_distance, settings.seed)
}

/// How a CPU render accumulates its points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accumulation {
    /// One framebuffer per thread, merged at the end: fastest for small images, whose copies
    /// stay in the caches.
    PerThread,
    /// One framebuffer shared by all threads ([`SharedFramebuffer`]): memory does not grow with
    /// the thread count.
    Shared,
}

impl Accumulation {
    /// Per-thread framebuffers take at most this many bytes together; beyond, one is shared.
    pub const PER_THREAD_BUDGET_BYTES: u64 = 64 << 20;

    /// The way for a render of `view` on the current rayon pool: per thread while all the
    /// copies fit [`Self::PER_THREAD_BUDGET_BYTES`], else shared.
    pub fn for_view(view: &SplatView) -> Self {
        let threads = rayon::current_num_threads().max(1) as u64;
        if view.accumulation_bytes().saturating_mul(threads) <= Self::PER_THREAD_BUDGET_BYTES {
            Accumulation::PerThread
        } else {
            Accumulation::Shared
        }
    }
}

/// The scene's camera at `t_secs`, its open fields filled from `bounds`; where the scene leaves
/// both target and distance open, fitted to `sample`, points of the attractor (tighter than
/// fitting its bounding box), for an image of aspect `aspect` (width / height).
pub fn frame_camera(scene: &Scene, t_secs: f64, bounds: (DVec3, DVec3), sample: &[Vec3], aspect: f32) -> OrbitCamera {
    let mut camera = scene.camera_for_at(t_secs, bounds);
    let spec = scene.camera_at(t_secs);
    if spec.target.is_none() && spec.distance.is_none() {
        camera.fit_points(sample, aspect);
    }
    camera
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        let text = "version = 1\n[grid]\nx = [0, 1]\ny = [0, 1]\n\
            [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\n\
            [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0.5, 0]\n\
            [[function]]\nkind = \"affine\"\nmatrix = [[0.5, 0], [0, 0.5]]\noffset = [0, 0.5]\n";
        Scene::parse(text, "sierpinski").unwrap()
    }

    /// The shot holds what its parts would give when prepared one by one.
    #[test]
    fn prepare_composes_the_steps() {
        let scene = scene();
        let settings = RenderSettings { width: 64, height: 48, points: 1000, ..scene.render.clone() };
        let shot = Shot::prepare(&scene, 0.0, &settings, Framing::Scene, None).unwrap();
        let compiled = CompiledIfs::new(&scene.at(0.0)).unwrap();
        assert_eq!(shot.compiled, compiled);
        assert_eq!(shot.bounds, chaos_game::attractor_bounds(&compiled, FRAMING_SEED));
        assert_eq!(shot.camera, scene.camera_for_at(0.0, shot.bounds));
        assert_eq!(shot.plan, ChunkPlan::new(1000).unwrap());
        assert_eq!((shot.view.width, shot.view.height), (64, 48));
        assert_eq!(shot.stream, 0);

        let bounds = (DVec3::splat(-2.0), DVec3::splat(2.0));
        let given = OrbitCamera::framing(bounds, 2);
        let shot = Shot::prepare(&scene, 0.0, &settings, Framing::Given(given), Some(bounds)).unwrap();
        assert_eq!((shot.bounds, shot.camera), (bounds, given));
    }

    /// Plant 2 at 160×120 framed for seeds 1 and 2 and twice the points: the same bounds and
    /// camera, bit for bit (they come from the fixed framing stream, not the render's seed).
    #[test]
    fn framing_is_the_same_for_every_seed_and_point_count() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/plant2.toml");
        let scene = Scene::load(&path).unwrap();
        let spec = scene.camera_at(0.0);
        assert!(spec.target.is_none() && spec.distance.is_none(), "plant2 must leave the fit to the sample");
        let shot = |seed: u32, points: u64| {
            let settings = RenderSettings { width: 160, height: 120, seed, points, ..scene.render.clone() };
            let shot = Shot::prepare(&scene, 0.0, &settings, Framing::Fit, None).unwrap();
            (shot.bounds, shot.camera)
        };
        let first = shot(1, 4_000_000);
        assert_eq!(shot(2, 4_000_000), first, "seed 2 frames otherwise than seed 1");
        assert_eq!(shot(1, 8_000_000), first, "twice the points frame otherwise");
        assert_eq!(shot(FRAMING_SEED + 1, 1000), first);
    }

    #[test]
    fn bad_shots_are_errors() {
        let mut scene = scene();
        scene.functions.iter_mut().for_each(|f| f.enabled = false);
        let settings = scene.render.clone();
        let err = Shot::prepare(&scene, 1.5, &settings, Framing::Fit, None).unwrap_err();
        assert_eq!(err, ShotError::NoFunctions { t_secs: 1.5 });
        let scene = self::tests::scene();
        let settings = RenderSettings { points: u64::MAX, ..settings };
        let err = Shot::prepare(&scene, 0.0, &settings, Framing::Fit, None).unwrap_err();
        assert!(matches!(err, ShotError::Points(_)), "{err}");
    }
}
