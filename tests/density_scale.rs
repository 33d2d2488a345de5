//! The absolute density scale (`[render] density_scale = "absolute"`) against its closed form.
//! Four affine maps of scale ½ tile the unit square, so the attractor's measure is uniform on it:
//! one per square unit. A pixel of area A inside it receives count ≈ N · A of N points drawn,
//! so its density log(1 + count / (N · A)) converges to ln 2 whatever N, the image's size or the
//! camera's zoom; white points over black at exposure 0 and gamma 1 draw it as linear ln 2,
//! the byte 255 · sRGB(ln 2) ≈ 216.9. Both routes, the CPU's and the GPU's chaos game. The relative scale, log(1 + count) / log(1 + max count),
//! has no such fixed point: it brightens towards 1 as the points grow.

mod common;

use nlifs::gpu::GpuContext;
use nlifs::render::render_cpu;
use nlifs::scene::Scene;
use nlifs::shot::{Framing, Shot};

/// The square scene seen from `distance` (a parallel camera with a 30° field: it shows
/// 2 · distance · tan 15° units of height) on `size_px`² pixels with `points` points.
fn square(scale: &str, distance: f64, size_px: u32, points: u64) -> Scene {
    let maps: String = [[0.0, 0.0], [0.5, 0.0], [0.0, 0.5], [0.5, 0.5]]
        .iter()
        .enumerate()
        .map(|(i, [x, y])| {
            format!(
                "[[function]]\nname = \"w{i}\"\nkind = \"affine\"\ncolor = \"#ffffff\"\n\
                 matrix = [[0.5, 0], [0, 0.5]]\noffset = [{x}, {y}]\n\n"
            )
        })
        .collect();
    let text = format!(
        "version = 1\nname = \"square\"\n\n[grid]\nx = [0, 1]\ny = [0, 1]\n\n{maps}\
         [camera]\ntarget = [0.5, 0.5, 0]\nyaw_deg = 0\npitch_deg = 0\ndistance = {distance}\n\
         fov_y_deg = 30\nprojection = \"parallel\"\n\n\
         [render]\nwidth = {size_px}\nheight = {size_px}\npoints = {points}\nmode = \"density\"\n\
         background = \"#000000\"\ndepth_cue = 0.0\ndensity_scale = \"{scale}\"\n"
    );
    Scene::parse(&text, "square.toml").unwrap()
}

/// The mean byte of the pixels well inside the square (two pixels from its edges) of a render
/// of `scene` (on the GPU where `gpu` is given), and how many there are.
fn inside_mean(scene: &Scene, gpu: Option<&GpuContext>) -> (f64, usize) {
    let shot = Shot::prepare(scene, 0.0, &scene.render, Framing::Scene, None).unwrap();
    let image = match gpu {
        Some(ctx) => nlifs::gpu::render::render_gpu(ctx, &shot).unwrap().image,
        None => render_cpu(&shot, &|_, _| {}).image,
    };
    let camera = &shot.camera;
    let half = f64::from(camera.half_height_at_target());
    let size = f64::from(image.height());
    // Pixel centre → scene coordinate (parallel, the target in the middle, +y up).
    let at = |px: u32| 0.5 + (f64::from(px) + 0.5 - 0.5 * size) * 2.0 * half / size;
    let margin = 2.0 * 2.0 * half / size;
    let inside = |v: f64| v > margin && v < 1.0 - margin;
    let (mut sum, mut n) = (0.0, 0);
    for (x, y, px) in image.enumerate_pixels() {
        if inside(at(x)) && inside(1.0 - at(y)) {
            sum += f64::from(px[0]) + f64::from(px[1]) + f64::from(px[2]);
            n += 3;
        }
    }
    assert!(n > 3 * 400, "only {} pixels inside the square", n / 3);
    (sum / n as f64, n / 3)
}

/// 255 · sRGB(ln 2): the byte a pixel of density one per square unit converges to.
fn ln2_byte() -> f64 {
    255.0 * f64::from(nlifs::color::linear_to_srgb(std::f32::consts::LN_2))
}

#[test]
fn absolute_density_converges_to_the_closed_form_whatever_the_points_and_zoom() {
    let expected = ln2_byte();
    // The square spans half the height, the whole height, and 2/3 of it; 48, 64 and 96 pixels.
    let cases = [(3.732, 64, 1_000_000), (3.732, 64, 4_000_000), (1.866, 48, 1_000_000), (2.8, 96, 3_000_000)];
    let ctx = common::gpu();
    let routes = [None, ctx.as_ref()];
    for ((distance, size_px, points), gpu) in cases.into_iter().flat_map(|c| routes.map(|r| (c, r))) {
        let route = if gpu.is_some() { "GPU" } else { "CPU" };
        let (mean, pixels) = inside_mean(&square("absolute", distance, size_px, points), gpu);
        // Per pixel N · A ≥ 434 points: a standard deviation ≤ 1/√434 ≈ 4.8 % of the count,
        // ≤ 3.5 % of ln(1 + d) at d = 1 (the slope d / ((1 + d) ln(1 + d)) = 0.72), ≤ 0.2 % of
        // the mean over ≥ 500 pixels: a fraction of a level (the sRGB slope there is about 0.6
        // levels per 1 %). 1.5 levels allowed.
        assert!(
            (mean - expected).abs() < 1.5,
            "{route}: distance {distance}, {size_px} px, {points} points: mean {mean:.2} over {pixels} pixels, \
             closed form {expected:.2}"
        );
    }
}

#[test]
fn relative_density_brightens_as_points_grow() {
    // The contrast the absolute scale removes: the same square, relative, at 1 and 16 M points.
    let (few, _) = inside_mean(&square("relative", 3.732, 64, 1_000_000), None);
    let (many, _) = inside_mean(&square("relative", 3.732, 64, 16_000_000), None);
    assert!(many > few + 1.0, "relative scale: {few:.2} at 1 M points, {many:.2} at 16 M");
}

/// `render --density-scale absolute` over a relative scene draws the absolute picture (the
/// bytes of the scene that sets it); a scale it does not know exits 2 and writes nothing.
#[test]
fn render_takes_the_density_scale_from_the_command_line() {
    let dir = common::temp_dir("density-scale");
    let write = |scale: &str| {
        let path = dir.join(format!("{scale}.toml"));
        std::fs::write(&path, square(scale, 3.732, 64, 200_000).to_toml()).unwrap();
        path.to_str().unwrap().to_string()
    };
    let (relative, absolute) = (write("relative"), write("absolute"));
    let out = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let render = |args: &[&str]| common::run_nlifs(&[&["render"], args].concat());
    assert!(render(&[&absolute, "-o", &out("scene.png")]).status.success());
    assert!(render(&[&relative, "--density-scale", "absolute", "-o", &out("flag.png")]).status.success());
    assert!(render(&[&relative, "-o", &out("relative.png")]).status.success());
    let pixels = |name: &str| image::open(dir.join(name)).unwrap().to_rgb8().into_raw();
    assert_eq!(pixels("flag.png"), pixels("scene.png"), "the flag draws what the scene's field draws");
    assert_ne!(pixels("flag.png"), pixels("relative.png"));
    let o = render(&[&relative, "--density-scale", "linear", "-o", &out("bad.png")]);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("relative or absolute"));
    assert!(!dir.join("bad.png").exists());
}
