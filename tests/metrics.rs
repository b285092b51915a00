//! HDR-FLIP and LDR-FLIP against NVIDIA's implementation.
//!
//! `flip_matches_nvidia_on_synthetic_pairs` always runs: two synthetic image pairs (built by the
//! formulas of tools/flip_reference_values.py) against the means NVIDIA's own FLIP
//! (`flip-evaluator` 1.7 from PyPI) prints for them; that script says how to reproduce them.
//!
//! The other two checks need outside files or take long, and are ignored by default:
//!
//! `FLIP_IMAGES=/path/to/flip/images cargo test --test metrics -- --ignored nvidia_published`
//! checks FLIP against NVIDIA's published means for the image pair in the FLIP repository
//! (github.com/NVlabs/flip, images/reference.{png,exr} and images/test.{png,exr}); their test
//! script expects 0.159691 (LDR) and 0.283478 (HDR, exposures -12.5423 to 0.9427 in 14 steps).
//!
//! `cargo test --test metrics -- --ignored --nocapture timings_1080p` prints how long each metric
//! takes on a 1920x1080 pair.

use ash::vk;
use hybrid_rt::image_io::{CpuImage, Texels, read_exr_rgba};
use hybrid_rt::metrics::{self, DEFAULT_PPD, HdrFlipOptions, LdrInput};
use std::path::Path;
use std::time::Instant;

fn rgb(width: u32, height: u32, f: impl Fn(u32, u32, usize) -> f32) -> CpuImage {
    let texels = (0..height)
        .flat_map(|y| (0..width).flat_map(move |x| (0..3).map(move |c| (x, y, c))))
        .map(|(x, y, c)| f(x, y, c))
        .collect();
    CpuImage { width, height, channels: 3, texels: Texels::F32(texels), format: vk::Format::UNDEFINED }
}

fn load_png(path: &Path) -> CpuImage {
    let img = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    let (w, h) = img.dimensions();
    rgb(w, h, |x, y, c| img.get_pixel(x, y)[c] as f32 / 255.0)
}

/// The pairs of tools/flip_reference_values.py, same formulas, computed in f64 and stored as f32.
fn synthetic_pairs() -> ((CpuImage, CpuImage), (CpuImage, CpuImage)) {
    let (w, h) = (160, 120);
    let ldr_ref = |x: u32, y: u32, c: usize| {
        let (x, y, c) = (x as f64, y as f64, c as f64);
        0.5 + 0.4 * (0.21 * x + 1.3 * c).sin() * (0.17 * y).cos()
    };
    let ldr_test = |x: u32, y: u32, c: usize| {
        let mut e = 0.08 * (0.9 * x as f64 + 0.7 * y as f64 + c as f64).sin();
        if (60..72).contains(&x) && (40..52).contains(&y) {
            e += 0.35;
        }
        (ldr_ref(x, y, c) + e).clamp(0.0, 1.0)
    };
    let hdr_ref = |x: u32, y: u32, c: usize| {
        let (x, y, c) = (x as f64, y as f64, c as f64);
        (5.0 * (0.05 * x + 0.4 * c).sin() * (0.043 * y).cos()).exp2()
    };
    let hdr_test = |x: u32, y: u32, c: usize| {
        let mut f = 1.0 + 0.2 * (0.8 * x as f64 + 1.1 * y as f64 + c as f64).sin();
        if (100..110).contains(&x) && (20..30).contains(&y) {
            f *= 8.0;
        }
        hdr_ref(x, y, c) * f
    };
    let img = |f: &dyn Fn(u32, u32, usize) -> f64| rgb(w, h, |x, y, c| f(x, y, c) as f32);
    ((img(&ldr_ref), img(&ldr_test)), (img(&hdr_ref), img(&hdr_test)))
}

#[test]
fn flip_matches_nvidia_on_synthetic_pairs() {
    let ((lr, lt), (hr, ht)) = synthetic_pairs();
    let ldr = metrics::ldr_flip(&lr, &lt, LdrInput::Srgb, DEFAULT_PPD, false).unwrap().mean;
    // NVIDIA flip-evaluator 1.7: 0.156950 (printed to six places).
    assert!((ldr - 0.156_950).abs() < 2e-5, "LDR-FLIP {ldr}, NVIDIA's 0.156950");
    let hdr = metrics::hdr_flip(&hr, &ht, &HdrFlipOptions::default()).unwrap();
    let e = hdr.exposures.unwrap();
    // NVIDIA: exposures -3.8205 to 1.1344 in 5 steps, mean 0.098864.
    assert!((e.start + 3.8205).abs() < 1e-3 && (e.stop - 1.1344).abs() < 1e-3 && e.count == 5, "{e:?}");
    assert!((hdr.mean - 0.098_864).abs() < 2e-5, "HDR-FLIP {}, NVIDIA's 0.098864", hdr.mean);
}

#[test]
#[ignore = "needs NVIDIA's FLIP images; set FLIP_IMAGES to their folder"]
fn nvidia_published_values() {
    let dir = std::env::var("FLIP_IMAGES").expect("set FLIP_IMAGES to the folder holding reference.png etc.");
    let dir = Path::new(&dir);
    let (r, t) = (load_png(&dir.join("reference.png")), load_png(&dir.join("test.png")));
    let ldr = metrics::ldr_flip(&r, &t, LdrInput::Srgb, DEFAULT_PPD, false).unwrap().mean;
    assert!((ldr - 0.159_691).abs() < 1e-5, "LDR-FLIP {ldr}");

    let (r, t) = (read_exr_rgba(&dir.join("reference.exr")).unwrap(), read_exr_rgba(&dir.join("test.exr")).unwrap());
    let hdr = metrics::hdr_flip(&r, &t, &HdrFlipOptions::default()).unwrap();
    let e = hdr.exposures.unwrap();
    assert!((e.start + 12.5423).abs() < 1e-3 && (e.stop - 0.9427).abs() < 1e-3 && e.count == 14, "{e:?}");
    assert!((hdr.mean - 0.283_478).abs() < 1e-5, "HDR-FLIP {}", hdr.mean);
}

#[test]
#[ignore = "timing only"]
fn timings_1080p() {
    let (w, h) = (1920, 1080);
    // Smooth HDR content over 2^-6 .. 2^6 (several HDR-FLIP exposures) with a small patterned error.
    let wave = |x: u32, y: u32, c: usize| (6.0 * (x as f32 * 0.01 + c as f32).sin() * (y as f32 * 0.007).cos()).exp2();
    let error = |x: u32, y: u32| 1.0 + 0.1 * (((x * 7 + y * 13) % 17) as f32 / 17.0 - 0.5);
    let r = rgb(w, h, wave);
    let t = rgb(w, h, |x, y, c| wave(x, y, c) * error(x, y));
    let (lr, lt) = (rgb(w, h, |x, y, c| wave(x, y, c) / 64.0), rgb(w, h, |x, y, c| wave(x, y, c) * error(x, y) / 64.0));
    let time = |name: &str, f: &dyn Fn() -> f64| {
        let start = Instant::now();
        let v = f();
        println!("{name:>10}: {v:.6} in {:.2} s", start.elapsed().as_secs_f64());
    };
    time("psnr", &|| metrics::psnr(&r, &t, 8.0).unwrap());
    time("ssim", &|| metrics::ssim(&r, &t).unwrap());
    time("ldr_flip", &|| metrics::ldr_flip(&lr, &lt, LdrInput::Linear, DEFAULT_PPD, false).unwrap().mean);
    time("hdr_flip", &|| {
        let result = metrics::hdr_flip(&r, &t, &HdrFlipOptions::default()).unwrap();
        println!("{:>10}  {:?}", "", result.exposures.unwrap());
        result.mean
    });
}
