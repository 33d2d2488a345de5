// flam3's variations 0–49 (linear … disc2), twin of src/flame/variations_basic.rs (`eval` and
// `eval_arithmetic`): the same arms in the same order with the same constants (`prepare` runs on
// the CPU; k0 = k[0..4], k1 = k[4..8]). flam3's oddities are kept as there.
//
// The arguments: variation `v`, weight `w`, constants `k0`, `k1`, the affine image's quantities
// `pt` = (tx, ty, tx² + ty², |t|) and `angles` = (atan2(tx, ty), tx / |t|, ty / |t|,
// atan2(ty, tx)), the chain's generator `rng`. Returns w · V(t).
fn variation_basic(
    v: u32,
    w: f32,
    k0: vec4<f32>,
    k1: vec4<f32>,
    pt: vec4<f32>,
    angles: vec4<f32>,
    rng: ptr<function, u32>,
) -> vec2<f32> {
    let x = pt.x;
    let y = pt.y;
    let r2 = pt.z;
    let r = pt.w;
    let a = angles.x;
    let sa = angles.y;
    let ca = angles.z;
    let ayx = angles.w;
    switch v {
        // linear
        case 0u: {
            if !flame_uses(0u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * x, w * y);
        }
        // sinusoidal
        case 1u: {
            if !flame_uses(1u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * sin(x), w * sin(y));
        }
        // spherical
        case 2u: {
            if !flame_uses(2u) {
                return vec2<f32>(0.0);
            }
            let f = w / (r2 + EPS);
            return vec2<f32>(f * x, f * y);
        }
        // swirl
        case 3u: {
            if !flame_uses(3u) {
                return vec2<f32>(0.0);
            }
            let s = sin(r2);
            let c = cos(r2);
            return vec2<f32>(w * (s * x - c * y), w * (c * x + s * y));
        }
        // horseshoe
        case 4u: {
            if !flame_uses(4u) {
                return vec2<f32>(0.0);
            }
            let f = w / (r + EPS);
            return vec2<f32>((x - y) * (x + y) * f, 2.0 * x * y * f);
        }
        // polar
        case 5u: {
            if !flame_uses(5u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * (a * FRAC_1_PI), w * (r - 1.0));
        }
        // handkerchief
        case 6u: {
            if !flame_uses(6u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * r * sin(a + r), w * r * cos(a - r));
        }
        // heart
        case 7u: {
            if !flame_uses(7u) {
                return vec2<f32>(0.0);
            }
            let f = w * r;
            return vec2<f32>(f * sin(r * a), -f * cos(r * a));
        }
        // disc
        case 8u: {
            if !flame_uses(8u) {
                return vec2<f32>(0.0);
            }
            let aa = a * FRAC_1_PI;
            return vec2<f32>(w * sin(PI * r) * aa, w * cos(PI * r) * aa);
        }
        // spiral
        case 9u: {
            if !flame_uses(9u) {
                return vec2<f32>(0.0);
            }
            let rr = r + EPS;
            let f = w / rr;
            return vec2<f32>(f * (ca + sin(rr)), f * (sa - cos(rr)));
        }
        // hyperbolic
        case 10u: {
            if !flame_uses(10u) {
                return vec2<f32>(0.0);
            }
            let rr = r + EPS;
            return vec2<f32>(w * sa / rr, w * ca * rr);
        }
        // diamond
        case 11u: {
            if !flame_uses(11u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * sa * cos(r), w * ca * sin(r));
        }
        // ex
        case 12u: {
            if !flame_uses(12u) {
                return vec2<f32>(0.0);
            }
            let n0 = sin(a + r);
            let n1 = cos(a - r);
            let m0 = n0 * n0 * n0 * r;
            let m1 = n1 * n1 * n1 * r;
            return vec2<f32>(w * (m0 + m1), w * (m0 - m1));
        }
        // julia: one of the two square roots, by a random bit.
        case 13u: {
            if !flame_uses(13u) {
                return vec2<f32>(0.0);
            }
            var aa = 0.5 * a;
            if (pcg_next_u32(rng) & 1u) != 0u {
                aa += PI;
            }
            let f = w * sqrt(r);
            return vec2<f32>(f * cos(aa), f * sin(aa));
        }
        // bent
        case 14u: {
            if !flame_uses(14u) {
                return vec2<f32>(0.0);
            }
            let nx = select(x, x * 2.0, x < 0.0);
            let ny = select(y, y / 2.0, y < 0.0);
            return vec2<f32>(w * nx, w * ny);
        }
        // waves
        case 15u: {
            if !flame_uses(15u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * (x + k0.x * sin(y * k0.z)), w * (y + k0.y * sin(x * k0.w)));
        }
        // fisheye (flam3's, with the output axes swapped)
        case 16u: {
            if !flame_uses(16u) {
                return vec2<f32>(0.0);
            }
            let f = 2.0 * w / (r + 1.0);
            return vec2<f32>(f * y, f * x);
        }
        // popcorn
        case 17u: {
            if !flame_uses(17u) {
                return vec2<f32>(0.0);
            }
            let dx = tan(3.0 * y);
            let dy = tan(3.0 * x);
            return vec2<f32>(w * (x + k0.x * sin(dx)), w * (y + k0.y * sin(dy)));
        }
        // exponential
        case 18u: {
            if !flame_uses(18u) {
                return vec2<f32>(0.0);
            }
            let dx = w * exp(x - 1.0);
            return vec2<f32>(dx * cos(PI * y), dx * sin(PI * y));
        }
        // power
        case 19u: {
            if !flame_uses(19u) {
                return vec2<f32>(0.0);
            }
            let f = w * pow_c(r, sa);
            return vec2<f32>(f * ca, f * sa);
        }
        // cosine
        case 20u: {
            if !flame_uses(20u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * (cos(x * PI) * cosh(y)), w * (-sin(x * PI) * sinh(y)));
        }
        // rings
        case 21u: {
            if !flame_uses(21u) {
                return vec2<f32>(0.0);
            }
            let dx = k0.x;
            let f = w * (fmod_c(r + dx, 2.0 * dx) - dx + r * (1.0 - dx));
            return vec2<f32>(f * ca, f * sa);
        }
        // fan
        case 22u: {
            if !flame_uses(22u) {
                return vec2<f32>(0.0);
            }
            let dx = k0.x;
            let dy = k0.y;
            let dx2 = 0.5 * dx;
            let aa = a + select(dx2, -dx2, fmod_c(a + dy, dx) > dx2);
            let f = w * r;
            return vec2<f32>(f * cos(aa), f * sin(aa));
        }
        // blob
        case 23u: {
            if !flame_uses(23u) {
                return vec2<f32>(0.0);
            }
            let f = r * (k0.x + k0.y * (0.5 + 0.5 * sin(k0.z * a)));
            return vec2<f32>(w * sa * f, w * ca * f);
        }
        // pdj
        case 24u: {
            if !flame_uses(24u) {
                return vec2<f32>(0.0);
            }
            let nx1 = cos(k0.y * x);
            let nx2 = sin(k0.z * x);
            let ny1 = sin(k0.x * y);
            let ny2 = cos(k0.w * y);
            return vec2<f32>(w * (ny1 - nx1), w * (nx2 - ny2));
        }
        // fan2
        case 25u: {
            if !flame_uses(25u) {
                return vec2<f32>(0.0);
            }
            let dx = k0.x;
            let dy = k0.y;
            let dx2 = 0.5 * dx;
            let t = a + dy - dx * f32(c_int((a + dy) / dx));
            let aa = select(a + dx2, a - dx2, t > dx2);
            let f = w * r;
            return vec2<f32>(f * sin(aa), f * cos(aa));
        }
        // rings2
        case 26u: {
            if !flame_uses(26u) {
                return vec2<f32>(0.0);
            }
            let dx = k0.x;
            let f = r + (-2.0 * dx * f32(c_int((r + dx) / (2.0 * dx))) + r * (1.0 - dx));
            return vec2<f32>(w * sa * f, w * ca * f);
        }
        // eyefish
        case 27u: {
            if !flame_uses(27u) {
                return vec2<f32>(0.0);
            }
            let f = (w * 2.0) / (r + 1.0);
            return vec2<f32>(f * x, f * y);
        }
        // bubble
        case 28u: {
            if !flame_uses(28u) {
                return vec2<f32>(0.0);
            }
            let f = w / (0.25 * r2 + 1.0);
            return vec2<f32>(f * x, f * y);
        }
        // cylinder
        case 29u: {
            if !flame_uses(29u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * sin(x), w * y);
        }
        // perspective
        case 30u: {
            if !flame_uses(30u) {
                return vec2<f32>(0.0);
            }
            let t = 1.0 / (k0.x - y * k0.y);
            return vec2<f32>(w * k0.x * x * t, w * k0.z * y * t);
        }
        // noise
        case 31u: {
            if !flame_uses(31u) {
                return vec2<f32>(0.0);
            }
            let ang = flame_random(rng) * 2.0 * PI;
            let f = w * flame_random(rng);
            return vec2<f32>(x * f * cos(ang), y * f * sin(ang));
        }
        // julian: one of |power| branches of t^(dist/power).
        case 32u: {
            if !flame_uses(32u) {
                return vec2<f32>(0.0);
            }
            let branch = f32(c_int(k0.y * flame_random(rng)));
            let ang = (ayx + 2.0 * PI * branch) / k0.x;
            let f = w * pow_c(r2, k0.z);
            return vec2<f32>(f * cos(ang), f * sin(ang));
        }
        // juliascope: as julian, the odd branches mirrored.
        case 33u: {
            if !flame_uses(33u) {
                return vec2<f32>(0.0);
            }
            let branch = trunc(k0.y * flame_random(rng));
            let even = fmod_c(branch, 2.0) == 0.0;
            let ang = select((2.0 * PI * branch - ayx) / k0.x, (2.0 * PI * branch + ayx) / k0.x, even);
            let f = w * pow_c(r2, k0.z);
            return vec2<f32>(f * cos(ang), f * sin(ang));
        }
        // blur
        case 34u: {
            if !flame_uses(34u) {
                return vec2<f32>(0.0);
            }
            let ang = flame_random(rng) * 2.0 * PI;
            let f = w * flame_random(rng);
            return vec2<f32>(f * cos(ang), f * sin(ang));
        }
        // gaussian_blur
        case 35u: {
            if !flame_uses(35u) {
                return vec2<f32>(0.0);
            }
            let ang = flame_random(rng) * 2.0 * PI;
            let f = w * pseudo_gaussian(rng);
            return vec2<f32>(f * cos(ang), f * sin(ang));
        }
        // radial_blur
        case 36u: {
            if !flame_uses(36u) {
                return vec2<f32>(0.0);
            }
            let g = w * pseudo_gaussian(rng);
            let ang = ayx + k0.x * g;
            let rz = k0.y * g - 1.0;
            return vec2<f32>(r * cos(ang) + rz * x, r * sin(ang) + rz * y);
        }
        // pie: slices, rotation, thickness
        case 37u: {
            if !flame_uses(37u) {
                return vec2<f32>(0.0);
            }
            let slice = f32(c_int(flame_random(rng) * k0.x + 0.5));
            let ang = k0.y + 2.0 * PI * (slice + flame_random(rng) * k0.z) / k0.x;
            let f = w * flame_random(rng);
            return vec2<f32>(f * cos(ang), f * sin(ang));
        }
        // ngon: 2π / sides, power / 2, circle, corners
        case 38u: {
            if !flame_uses(38u) {
                return vec2<f32>(0.0);
            }
            let r_factor = pow_c(r2, k0.y);
            let b = k0.x;
            var phi = ayx - b * floor(ayx / b);
            if phi > b / 2.0 {
                phi -= b;
            }
            let amp = (k0.w * (1.0 / (cos(phi) + EPS) - 1.0) + k0.z) / (r_factor + EPS);
            return vec2<f32>(w * x * amp, w * y * amp);
        }
        // curl
        case 39u: {
            if !flame_uses(39u) {
                return vec2<f32>(0.0);
            }
            let c1 = k0.x;
            let c2 = k0.y;
            let re = 1.0 + c1 * x + c2 * (x * x - y * y);
            let im = c1 * y + 2.0 * c2 * x * y;
            let f = w / (re * re + im * im);
            return vec2<f32>((x * re + y * im) * f, (y * re - x * im) * f);
        }
        // rectangles
        case 40u: {
            if !flame_uses(40u) {
                return vec2<f32>(0.0);
            }
            let rx = k0.x;
            let ry = k0.y;
            let nx = select((2.0 * floor(x / rx) + 1.0) * rx - x, x, rx == 0.0);
            let ny = select((2.0 * floor(y / ry) + 1.0) * ry - y, y, ry == 0.0);
            return vec2<f32>(w * nx, w * ny);
        }
        // arch
        case 41u: {
            if !flame_uses(41u) {
                return vec2<f32>(0.0);
            }
            let ang = flame_random(rng) * w * PI;
            let s = sin(ang);
            return vec2<f32>(w * s, w * (s * s) / cos(ang));
        }
        // tangent
        case 42u: {
            if !flame_uses(42u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * sin(x) / cos(y), w * tan(y));
        }
        // square
        case 43u: {
            if !flame_uses(43u) {
                return vec2<f32>(0.0);
            }
            let u = flame_random(rng);
            let s = flame_random(rng);
            return vec2<f32>(w * (u - 0.5), w * (s - 0.5));
        }
        // rays
        case 44u: {
            if !flame_uses(44u) {
                return vec2<f32>(0.0);
            }
            let ang = w * flame_random(rng) * PI;
            let f = w / (r2 + EPS);
            let t = w * tan(ang) * f;
            return vec2<f32>(t * cos(x), t * sin(y));
        }
        // blade
        case 45u: {
            if !flame_uses(45u) {
                return vec2<f32>(0.0);
            }
            let ang = flame_random(rng) * w * r;
            let s = sin(ang);
            let c = cos(ang);
            return vec2<f32>(w * x * (c + s), w * x * (c - s));
        }
        // secant2
        case 46u: {
            if !flame_uses(46u) {
                return vec2<f32>(0.0);
            }
            let cr = cos(w * r);
            let icr = 1.0 / cr;
            return vec2<f32>(w * x, select(w * (icr - 1.0), w * (icr + 1.0), cr < 0.0));
        }
        // twintrian
        case 47u: {
            if !flame_uses(47u) {
                return vec2<f32>(0.0);
            }
            let ang = flame_random(rng) * w * r;
            let s = sin(ang);
            // log10(s²)
            var diff = log(s * s) * 0.434294481903251827651 + cos(ang);
            if !(abs(diff) <= 1e10) {
                diff = -30.0;
            }
            return vec2<f32>(w * x * diff, w * x * (diff - s * PI));
        }
        // cross
        case 48u: {
            if !flame_uses(48u) {
                return vec2<f32>(0.0);
            }
            let s = x * x - y * y;
            let f = w * sqrt(1.0 / (s * s + EPS));
            return vec2<f32>(x * f, y * f);
        }
        // disc2: rot π, sin(twist)', cos(twist)' − 1
        case 49u: {
            if !flame_uses(49u) {
                return vec2<f32>(0.0);
            }
            let ang = k0.x * (x + y);
            let f = w * a / PI;
            return vec2<f32>((sin(ang) + k0.z) * f, (cos(ang) + k0.y) * f);
        }
        default: {
            return vec2<f32>(0.0);
        }
    }
}
