// flam3's variations 50–98 (super_shape … mobius) and the names after flam3's 99 (linear3D,
// flatten), twin of src/flame/variations_plugins.rs (`eval`): the same arms in the same order
// with the same constants (`prepare` runs on the CPU; k0 = k[0..4], k1 = k[4..8]). `pre_blur`
// (67) moves the affine image before every term (`apply_xform` in `variations.wgsl`).
//
// f32 care: the hyperbolic functions of cothe's complex variations (tan, sec, csc, cot, tanh,
// sech, csch, coth) and foci's exponentials overflow f32 past |argument| ≈ 89 where the CPU's
// f64 does not, and inf / inf would make a NaN (a re-seed) of what is there a finite limit. Their
// argument is clamped to ±40 (doubled: ±80) first; beyond it the f64 results equal their limits
// to better than f32's precision (the terms left out are below e^−40 relative).
const HYPERBOLIC_CLAMP: f32 = 40.0;

// floor((count·a + π) / 2π): the wedge a point's angle falls in (`wedge_index`).
fn wedge_index(count: f32, a: f32) -> f32 {
    return floor((count * a + PI) * FRAC_1_PI * 0.5);
}

// modulus' fold of one coordinate into [−m, m].
fn modulus(t: f32, m: f32) -> f32 {
    if t > m {
        return -m + fmod_c(t + m, 2.0 * m);
    } else if t < -m {
        return m - fmod_c(m - t, 2.0 * m);
    }
    return t;
}

// The arguments are `variation_basic`'s (`variations_basic.wgsl`).
fn variation_plugin(
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
    let ayx = angles.w;
    switch v {
        // super_shape: rnd, m/4, −1/n1, n2, n3, holes
        case 50u: {
            if !flame_uses(50u) {
                return vec2<f32>(0.0);
            }
            let ang = k0.y * ayx + FRAC_PI_4;
            let t1 = pow_c(abs(cos(ang)), k0.w);
            let t2 = pow_c(abs(sin(ang)), k1.x);
            let rnd = k0.x;
            let f = w * ((rnd * flame_random(rng) + (1.0 - rnd) * r) - k1.y) * pow_c(t1 + t2, k0.z) / r;
            return vec2<f32>(f * x, f * y);
        }
        // flower: petals, holes
        case 51u: {
            if !flame_uses(51u) {
                return vec2<f32>(0.0);
            }
            let f = w * (flame_random(rng) - k0.y) * cos(k0.x * ayx) / r;
            return vec2<f32>(f * x, f * y);
        }
        // conic: eccentricity, holes
        case 52u: {
            if !flame_uses(52u) {
                return vec2<f32>(0.0);
            }
            let ct = x / r;
            let f = w * (flame_random(rng) - k0.y) * k0.x / (1.0 + k0.x * ct) / r;
            return vec2<f32>(f * x, f * y);
        }
        // parabola: height, width
        case 53u: {
            if !flame_uses(53u) {
                return vec2<f32>(0.0);
            }
            let s = sin(r);
            let c = cos(r);
            let nx = k0.x * w * s * s * flame_random(rng);
            let ny = k0.y * w * c * flame_random(rng);
            return vec2<f32>(nx, ny);
        }
        // bent2: x, y
        case 54u: {
            if !flame_uses(54u) {
                return vec2<f32>(0.0);
            }
            let nx = select(x, x * k0.x, x < 0.0);
            let ny = select(y, y * k0.y, y < 0.0);
            return vec2<f32>(w * nx, w * ny);
        }
        // bipolar: shift
        case 55u: {
            if !flame_uses(55u) {
                return vec2<f32>(0.0);
            }
            let t = r2 + 1.0;
            let x2 = 2.0 * x;
            let ps = -FRAC_PI_2 * k0.x;
            var yy = 0.5 * atan2_c(2.0 * y, r2 - 1.0) + ps;
            if yy > FRAC_PI_2 {
                yy = -FRAC_PI_2 + fmod_c(yy + FRAC_PI_2, PI);
            } else if yy < -FRAC_PI_2 {
                yy = FRAC_PI_2 - fmod_c(FRAC_PI_2 - yy, PI);
            }
            return vec2<f32>(w * 0.25 * FRAC_2_PI * log((t + x2) / (t - x2)), w * FRAC_2_PI * yy);
        }
        // boarders (WGSL's round is C's rint: half to even)
        case 56u: {
            if !flame_uses(56u) {
                return vec2<f32>(0.0);
            }
            let rx = round(x);
            let ry = round(y);
            let ox = x - rx;
            let oy = y - ry;
            if flame_random(rng) >= 0.75 {
                return vec2<f32>(w * (ox * 0.5 + rx), w * (oy * 0.5 + ry));
            } else if abs(ox) >= abs(oy) {
                if ox >= 0.0 {
                    return vec2<f32>(w * (ox * 0.5 + rx + 0.25), w * (oy * 0.5 + ry + 0.25 * oy / ox));
                }
                return vec2<f32>(w * (ox * 0.5 + rx - 0.25), w * (oy * 0.5 + ry - 0.25 * oy / ox));
            } else if oy >= 0.0 {
                return vec2<f32>(w * (ox * 0.5 + rx + ox / oy * 0.25), w * (oy * 0.5 + ry + 0.25));
            }
            return vec2<f32>(w * (ox * 0.5 + rx - ox / oy * 0.25), w * (oy * 0.5 + ry - 0.25));
        }
        // butterfly: 4 / √(3π) · w
        case 57u: {
            if !flame_uses(57u) {
                return vec2<f32>(0.0);
            }
            let wx = w * 1.3029400317411198;
            let y2 = y * 2.0;
            let f = wx * sqrt(abs(y * x) / (EPS + x * x + y2 * y2));
            return vec2<f32>(f * x, f * y2);
        }
        // cell: size
        case 58u: {
            if !flame_uses(58u) {
                return vec2<f32>(0.0);
            }
            let size = k0.x;
            let inv = 1.0 / size;
            // The cell's index as C's int (size 0 gives i32::MIN, times 0: flam3's (w·x, −w·y)).
            let cx = c_int(floor(x * inv));
            let cy = c_int(floor(y * inv));
            let dx = x - f32(cx) * size;
            let dy = y - f32(cy) * size;
            // Interleave the four quadrants' cells on the positive ones (i32 arithmetic wraps).
            let fx = select(-(cx * 2 + 1), cx * 2, cx >= 0);
            let fy = select(-(cy * 2 + 1), cy * 2, cy >= 0);
            return vec2<f32>(w * (dx + f32(fx) * size), -(w * (dy + f32(fy) * size)));
        }
        // cpow: 2π/power, r/power, i/power, power
        case 59u: {
            if !flame_uses(59u) {
                return vec2<f32>(0.0);
            }
            let lnr = 0.5 * log(r2);
            let ang = k0.y * ayx + k0.z * lnr + k0.x * floor(k0.w * flame_random(rng));
            let m = w * exp(k0.y * lnr - k0.z * ayx);
            return vec2<f32>(m * cos(ang), m * sin(ang));
        }
        // curve: xamp, yamp, xlength², ylength²
        case 60u: {
            if !flame_uses(60u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * (x + k0.x * exp(-y * y / k0.z)), w * (y + k0.y * exp(-x * x / k0.w)));
        }
        // edisc
        case 61u: {
            if !flame_uses(61u) {
                return vec2<f32>(0.0);
            }
            let tmp = r2 + 1.0;
            let tmp2 = 2.0 * x;
            let xmax = (sqrt(tmp + tmp2) + sqrt(tmp - tmp2)) * 0.5;
            let a1 = log(xmax + sqrt(xmax - 1.0));
            let a2 = -acos(x / xmax);
            let ww = w / 11.57034632;
            let snv = select(sin(a1), -sin(a1), y > 0.0);
            return vec2<f32>(ww * cosh(a2) * cos(a1), ww * sinh(a2) * snv);
        }
        // elliptic
        case 62u: {
            if !flame_uses(62u) {
                return vec2<f32>(0.0);
            }
            let tmp = r2 + 1.0;
            let x2 = 2.0 * x;
            let xmax = 0.5 * (sqrt(tmp + x2) + sqrt(tmp - x2));
            let aa = x / xmax;
            let b0 = 1.0 - aa * aa;
            let ssx0 = xmax - 1.0;
            let ww = w / FRAC_PI_2;
            let b = select(sqrt(b0), 0.0, b0 < 0.0);
            let ssx = select(sqrt(ssx0), 0.0, ssx0 < 0.0);
            let l = log(xmax + ssx);
            return vec2<f32>(ww * atan2_c(aa, b), select(-(ww * l), ww * l, y > 0.0));
        }
        // escher: vc, vd
        case 63u: {
            if !flame_uses(63u) {
                return vec2<f32>(0.0);
            }
            let lnr = 0.5 * log(r2);
            let m = w * exp(k0.x * lnr - k0.y * ayx);
            let ang = k0.x * ayx + k0.y * lnr;
            return vec2<f32>(m * cos(ang), m * sin(ang));
        }
        // foci (x clamped, see the file's note)
        case 64u: {
            if !flame_uses(64u) {
                return vec2<f32>(0.0);
            }
            let xc = clamp(x, -2.0 * HYPERBOLIC_CLAMP, 2.0 * HYPERBOLIC_CLAMP);
            let expx = exp(xc) * 0.5;
            let expnx = 0.25 / expx;
            let t = w / (expx + expnx - cos(y));
            return vec2<f32>(t * (expx - expnx), t * sin(y));
        }
        // lazysusan: spin, space, twist, x, y
        case 65u: {
            if !flame_uses(65u) {
                return vec2<f32>(0.0);
            }
            let lx = k0.w;
            let ly = k1.x;
            let xx = x - lx;
            let yy = y + ly;
            let rr = sqrt(xx * xx + yy * yy);
            if rr < w {
                let ang = atan2_c(yy, xx) + k0.x + k0.z * (w - rr);
                let f = w * rr;
                return vec2<f32>(f * cos(ang) + lx, f * sin(ang) - ly);
            }
            let f = w * (1.0 + k0.y / rr);
            return vec2<f32>(f * xx + lx, f * yy - ly);
        }
        // loonie
        case 66u: {
            if !flame_uses(66u) {
                return vec2<f32>(0.0);
            }
            let w2 = w * w;
            if r2 < w2 {
                let f = w * sqrt(w2 / r2 - 1.0);
                return vec2<f32>(f * x, f * y);
            }
            return vec2<f32>(w * x, w * y);
        }
        // modulus: x, y
        case 68u: {
            if !flame_uses(68u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * modulus(x, k0.x), w * modulus(y, k0.y));
        }
        // oscilloscope: separation, frequency, amplitude, damping
        case 69u: {
            if !flame_uses(69u) {
                return vec2<f32>(0.0);
            }
            let tpf = 2.0 * PI * k0.y;
            var t = k0.z * cos(tpf * x) + k0.x;
            if k0.w != 0.0 {
                t = k0.z * exp(-abs(x) * k0.w) * cos(tpf * x) + k0.x;
            }
            return select(vec2<f32>(w * x, w * y), vec2<f32>(w * x, -(w * y)), abs(y) <= t);
        }
        // polar2
        case 70u: {
            if !flame_uses(70u) {
                return vec2<f32>(0.0);
            }
            let p2v = w / PI;
            return vec2<f32>(p2v * a, p2v / 2.0 * log(r2));
        }
        // popcorn2: x, y, c
        case 71u: {
            if !flame_uses(71u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * (x + k0.x * sin(tan(y * k0.z))), w * (y + k0.y * sin(tan(x * k0.z))));
        }
        // scry
        case 72u: {
            if !flame_uses(72u) {
                return vec2<f32>(0.0);
            }
            let f = 1.0 / (r * (r2 + 1.0 / (w + EPS)));
            return vec2<f32>(x * f, y * f);
        }
        // separation: x, xinside, y, yinside
        case 73u: {
            if !flame_uses(73u) {
                return vec2<f32>(0.0);
            }
            let sx = sqrt(x * x + k0.x * k0.x);
            let sy = sqrt(y * y + k0.z * k0.z);
            let nx = select(-(w * (sx + x * k0.y)), w * (sx - x * k0.y), x > 0.0);
            let ny = select(-(w * (sy + y * k0.w)), w * (sy - y * k0.w), y > 0.0);
            return vec2<f32>(nx, ny);
        }
        // split: xsize, ysize
        case 74u: {
            if !flame_uses(74u) {
                return vec2<f32>(0.0);
            }
            let ny = select(-(w * y), w * y, cos(x * k0.x * PI) >= 0.0);
            let nx = select(-(w * x), w * x, cos(y * k0.y * PI) >= 0.0);
            return vec2<f32>(nx, ny);
        }
        // splits: x, y
        case 75u: {
            if !flame_uses(75u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(
                select(w * (x - k0.x), w * (x + k0.x), x >= 0.0),
                select(w * (y - k0.y), w * (y + k0.y), y >= 0.0),
            );
        }
        // stripes: space, warp
        case 76u: {
            if !flame_uses(76u) {
                return vec2<f32>(0.0);
            }
            let rx = floor(x + 0.5);
            let ox = x - rx;
            return vec2<f32>(w * (ox * (1.0 - k0.x) + rx), w * (y + ox * ox * k0.y));
        }
        // wedge: angle, hole, count, swirl, compensation
        case 77u: {
            if !flame_uses(77u) {
                return vec2<f32>(0.0);
            }
            let aa = ayx + k0.w * r;
            let c = wedge_index(k0.z, aa);
            let ang = aa * k1.x + c * k0.x;
            let f = w * (r + k0.y);
            return vec2<f32>(f * cos(ang), f * sin(ang));
        }
        // wedge_julia: angle, count, power, cn, |power|, compensation
        case 78u: {
            if !flame_uses(78u) {
                return vec2<f32>(0.0);
            }
            let f = w * pow_c(r2, k0.w);
            let branch = f32(c_int(k1.x * flame_random(rng)));
            let aa = (ayx + 2.0 * PI * branch) / k0.z;
            let c = wedge_index(k0.y, aa);
            let ang = aa * k1.y + c * k0.x;
            return vec2<f32>(f * cos(ang), f * sin(ang));
        }
        // wedge_sph: angle, count, hole, swirl, compensation
        case 79u: {
            if !flame_uses(79u) {
                return vec2<f32>(0.0);
            }
            let rr = 1.0 / (r + EPS);
            let aa = ayx + k0.w * rr;
            let c = wedge_index(k0.y, aa);
            let ang = aa * k1.x + c * k0.x;
            let f = w * (rr + k0.z);
            return vec2<f32>(f * cos(ang), f * sin(ang));
        }
        // whorl: inside, outside
        case 80u: {
            if !flame_uses(80u) {
                return vec2<f32>(0.0);
            }
            let ang = select(ayx + k0.y / (w - r), ayx + k0.x / (w - r), r < w);
            return vec2<f32>(w * r * cos(ang), w * r * sin(ang));
        }
        // waves2: scalex, scaley, freqx, freqy
        case 81u: {
            if !flame_uses(81u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * (x + k0.x * sin(y * k0.z)), w * (y + k0.y * sin(x * k0.w)));
        }
        // exp
        case 82u: {
            if !flame_uses(82u) {
                return vec2<f32>(0.0);
            }
            let e = exp(x);
            return vec2<f32>(w * e * cos(y), w * e * sin(y));
        }
        // log
        case 83u: {
            if !flame_uses(83u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * 0.5 * log(r2), w * ayx);
        }
        // sin
        case 84u: {
            if !flame_uses(84u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * sin(x) * cosh(y), w * cos(x) * sinh(y));
        }
        // cos
        case 85u: {
            if !flame_uses(85u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * cos(x) * cosh(y), -(w * sin(x) * sinh(y)));
        }
        // tan (y clamped, see the file's note)
        case 86u: {
            if !flame_uses(86u) {
                return vec2<f32>(0.0);
            }
            let yc = clamp(y, -HYPERBOLIC_CLAMP, HYPERBOLIC_CLAMP);
            let den = 1.0 / (cos(2.0 * x) + cosh(2.0 * yc));
            return vec2<f32>(w * den * sin(2.0 * x), w * den * sinh(2.0 * yc));
        }
        // sec
        case 87u: {
            if !flame_uses(87u) {
                return vec2<f32>(0.0);
            }
            let yc = clamp(y, -HYPERBOLIC_CLAMP, HYPERBOLIC_CLAMP);
            let den = 2.0 / (cos(2.0 * x) + cosh(2.0 * yc));
            return vec2<f32>(w * den * cos(x) * cosh(yc), w * den * sin(x) * sinh(yc));
        }
        // csc
        case 88u: {
            if !flame_uses(88u) {
                return vec2<f32>(0.0);
            }
            let yc = clamp(y, -HYPERBOLIC_CLAMP, HYPERBOLIC_CLAMP);
            let den = 2.0 / (cosh(2.0 * yc) - cos(2.0 * x));
            return vec2<f32>(w * den * sin(x) * cosh(yc), -(w * den * cos(x) * sinh(yc)));
        }
        // cot
        case 89u: {
            if !flame_uses(89u) {
                return vec2<f32>(0.0);
            }
            let yc = clamp(y, -HYPERBOLIC_CLAMP, HYPERBOLIC_CLAMP);
            let den = 1.0 / (cosh(2.0 * yc) - cos(2.0 * x));
            return vec2<f32>(w * den * sin(2.0 * x), -(w * den) * sinh(2.0 * yc));
        }
        // sinh
        case 90u: {
            if !flame_uses(90u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * sinh(x) * cos(y), w * cosh(x) * sin(y));
        }
        // cosh
        case 91u: {
            if !flame_uses(91u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * cosh(x) * cos(y), w * sinh(x) * sin(y));
        }
        // tanh (x clamped)
        case 92u: {
            if !flame_uses(92u) {
                return vec2<f32>(0.0);
            }
            let xc = clamp(x, -HYPERBOLIC_CLAMP, HYPERBOLIC_CLAMP);
            let den = 1.0 / (cos(2.0 * y) + cosh(2.0 * xc));
            return vec2<f32>(w * den * sinh(2.0 * xc), w * den * sin(2.0 * y));
        }
        // sech (x clamped)
        case 93u: {
            if !flame_uses(93u) {
                return vec2<f32>(0.0);
            }
            let xc = clamp(x, -HYPERBOLIC_CLAMP, HYPERBOLIC_CLAMP);
            let den = 2.0 / (cos(2.0 * y) + cosh(2.0 * xc));
            return vec2<f32>(w * den * cos(y) * cosh(xc), -(w * den * sin(y) * sinh(xc)));
        }
        // csch (x clamped)
        case 94u: {
            if !flame_uses(94u) {
                return vec2<f32>(0.0);
            }
            let xc = clamp(x, -HYPERBOLIC_CLAMP, HYPERBOLIC_CLAMP);
            let den = 2.0 / (cosh(2.0 * xc) - cos(2.0 * y));
            return vec2<f32>(w * den * sinh(xc) * cos(y), -(w * den * cosh(xc) * sin(y)));
        }
        // coth (x clamped)
        case 95u: {
            if !flame_uses(95u) {
                return vec2<f32>(0.0);
            }
            let xc = clamp(x, -HYPERBOLIC_CLAMP, HYPERBOLIC_CLAMP);
            let den = 1.0 / (cosh(2.0 * xc) - cos(2.0 * y));
            return vec2<f32>(w * den * sinh(2.0 * xc), w * den * sin(2.0 * y));
        }
        // auger: freq, weight, sym, scale
        case 96u: {
            if !flame_uses(96u) {
                return vec2<f32>(0.0);
            }
            let s = sin(k0.x * x);
            let t = sin(k0.x * y);
            let dy = y + k0.y * (k0.w * s / 2.0 + abs(y) * s);
            let dx = x + k0.y * (k0.w * t / 2.0 + abs(x) * t);
            return vec2<f32>(w * (x + k0.z * (dx - x)), w * dy);
        }
        // flux: spread
        case 97u: {
            if !flame_uses(97u) {
                return vec2<f32>(0.0);
            }
            let xpw = x + w;
            let xmw = x - w;
            let avgr = w * (2.0 + k0.x) * sqrt(sqrt(y * y + xpw * xpw) / sqrt(y * y + xmw * xmw));
            let avga = (atan2_c(y, xmw) - atan2_c(y, xpw)) * 0.5;
            return vec2<f32>(avgr * cos(avga), avgr * sin(avga));
        }
        // mobius: (a t + b) / (c t + d) in complex numbers
        case 98u: {
            if !flame_uses(98u) {
                return vec2<f32>(0.0);
            }
            let re_u = k0.x * x - k0.y * y + k0.z;
            let im_u = k0.x * y + k0.y * x + k0.w;
            let re_v = k1.x * x - k1.y * y + k1.z;
            let im_v = k1.x * y + k1.y * x + k1.w;
            let rad_v = w / (re_v * re_v + im_v * im_v);
            return vec2<f32>(rad_v * (re_u * re_v + im_u * im_v), rad_v * (im_u * re_v - re_u * im_v));
        }
        // linear3D
        case 99u: {
            if !flame_uses(99u) {
                return vec2<f32>(0.0);
            }
            return vec2<f32>(w * x, w * y);
        }
        // flatten (z = 0 only) and anything unknown: nothing in the plane.
        default: {
            return vec2<f32>(0.0);
        }
    }
}
