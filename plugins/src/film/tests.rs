//! The film's tests.

use super::splat::{ceil_i64, floor_i64, table_index};
use super::*;
use crate::filters::{BoxFilter, GaussianFilter};

/// The f32 running statistics agree with sums in f64, also where the mean is large against
/// the spread (where E[x^2] - E[x]^2 in f32 would cancel to noise): the variance within
/// 0.5% when the spread is 1e-5 of the level (pbrt-v4 keeps its variance in f32 too),
/// 0.1% otherwise.
#[test]
fn pixel_statistics_keep_their_precision() {
    for (level, spread, tolerance) in [
        (1000.0f64, 0.01f64, 5e-3),
        (0.5, 0.4, 1e-3),
        (1e-3, 1e-3, 1e-3),
    ] {
        let mut stats = PixelStats::default();
        let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
        let n = 10_000;
        for i in 0..n {
            // A deterministic, irregular sequence around `level`.
            let x = (level + spread * ((i as f64 * 0.618_034).fract() - 0.5)) as f32;
            stats.add(Spectrum::new(x, x, x));
            sum += f64::from(x);
            sum_sq += f64::from(x) * f64::from(x);
        }
        let mean = sum / n as f64;
        let var_of_mean = (sum_sq / n as f64 - mean * mean) / (n as f64 - 1.0);
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
        assert!(rel(f64::from(stats.mean().x), mean) < 1e-6, "{level}");
        assert!(rel(stats.sum()[0], sum) < 1e-6, "{level}");
        assert!(rel(stats.sum_sq()[0], sum_sq) < 1e-6, "{level}");
        let v = f64::from(stats.variance_of_mean().x);
        assert!(
            rel(v, var_of_mean) < tolerance,
            "{level}: {v} against {var_of_mean}"
        );
    }
}

#[test]
fn integer_rounding_matches_libm() {
    let values = [
        0.0f32,
        -0.0,
        0.5,
        -0.5,
        1.0,
        -1.0,
        1.5,
        -1.5,
        2.999_999_8,
        -2.999_999_8,
        1e7 + 0.5,
        3.0e9,
        -3.0e9,
        1e30,
        -1e30,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
    ];
    for v in values {
        assert_eq!(ceil_i64(v), v.ceil() as i64, "ceil {v}");
        assert_eq!(floor_i64(v), v.floor() as i64, "floor {v}");
    }
    for r in [
        0.0f32,
        0.03,
        0.5,
        0.937_5,
        0.999_99,
        1.0,
        1.2,
        1e9,
        f32::INFINITY,
    ] {
        let want = ((r * TABLE_SIZE as f32) as usize).min(TABLE_SIZE - 1);
        assert_eq!(table_index(r) as usize, want, "{r}");
    }
}

/// Releasing the sums frees them and keeps the per-pixel statistics the output still reads.
#[test]
fn released_sums_leave_the_statistics() {
    let mut f = Film::new(
        FilmSettings::with_resolution(2, 1),
        &BoxFilter::new(0.5, 0.5),
    );
    f.add_sample(Vec2::new(0.25, 0.5), Spectrum::splat(1.0));
    f.add_sample(Vec2::new(1.5, 0.5), Spectrum::splat(5.0));
    let stats = f.pixel_stats().to_vec();
    f.release_sums();
    assert_eq!(f.weighted_sums().as_deref(), Some(&[][..]));
    assert!(f.pixels().is_empty());
    assert_eq!(f.pixel_stats(), &stats[..]);
}

#[test]
fn box_filter_averages_samples_in_the_pixel() {
    let mut f = Film::new(
        FilmSettings::with_resolution(2, 1),
        &BoxFilter::new(0.5, 0.5),
    );
    f.add_sample(Vec2::new(0.25, 0.5), Spectrum::splat(1.0));
    f.add_sample(Vec2::new(0.75, 0.5), Spectrum::splat(3.0));
    f.add_sample(Vec2::new(1.5, 0.5), Spectrum::splat(5.0));
    let p = f.pixels();
    assert_eq!(p[0], Spectrum::splat(2.0));
    assert_eq!(p[1], Spectrum::splat(5.0));
    let st = f.pixel_stats();
    assert_eq!((st[0].count, st[1].count), (2, 1));
    assert_eq!(st[0].mean(), Spectrum::splat(2.0));
    // Samples 1 and 3: sample variance 2, variance of the mean 1.
    assert_eq!(st[0].variance_of_mean(), Spectrum::splat(1.0));
    assert_eq!(st[1].variance_of_mean(), Spectrum::ZERO);
}

#[test]
fn batch_adding_equals_one_by_one() {
    use crate::filters::MitchellFilter;
    let kernel = MitchellFilter::new(2.0, 1.5, 1.0 / 3.0, 1.0 / 3.0);
    let mut s = FilmSettings::with_resolution(9, 7);
    s.crop = [1, 8, 1, 6];
    let mut one = Film::new(s.clone(), &kernel);
    let mut batch = Film::new(s, &kernel);
    // Row-sorted samples, several per pixel, with varied values.
    let mut samples = Vec::new();
    for py in 0..7u32 {
        for px in 0..9u32 {
            for k in 0..3u32 {
                let u = Vec2::new(
                    (k as f32 * 0.37 + px as f32 * 0.11) % 1.0,
                    (k as f32 * 0.61) % 1.0,
                );
                let l = Spectrum::new(px as f32, py as f32, k as f32 + 1.0);
                samples.push((Vec2::new(px as f32, py as f32) + u, l));
            }
        }
    }
    for &(p, l) in &samples {
        one.add_sample(p, l);
    }
    batch.add_samples(&samples[..100]);
    batch.add_samples(&samples[100..]);
    assert_eq!(one.pixels(), batch.pixels());
    assert_eq!(one.pixel_stats(), batch.pixel_stats());
    assert_eq!(batch.pixel_stats()[0].count, 3);
}

/// A film that counts its pixels' samples alone makes the same image and counts as one that
/// keeps their statistics, batch by batch or one by one, within a crop; only the moments are
/// gone (zero).
#[test]
fn a_film_that_counts_only_makes_the_same_image_and_counts() {
    use crate::filters::MitchellFilter;
    let kernel = MitchellFilter::new(2.0, 1.5, 1.0 / 3.0, 1.0 / 3.0);
    let mut s = FilmSettings::with_resolution(9, 7);
    s.crop = [1, 8, 1, 6];
    let mut full = Film::new(s.clone(), &kernel);
    let mut counted = Film::new(s.clone(), &kernel);
    let mut one_by_one = Film::new(s, &kernel);
    counted.count_only();
    one_by_one.count_only();
    assert!(full.keeps_moments() && !counted.keeps_moments());
    let mut samples = Vec::new();
    for py in 0..7u32 {
        for px in 0..9u32 {
            for k in 0..1 + (px + py) % 3 {
                let u = Vec2::new((k as f32 * 0.37 + 0.1) % 1.0, (k as f32 * 0.61 + 0.2) % 1.0);
                let l = Spectrum::new(px as f32, py as f32 + 0.5, k as f32 + 1.0);
                samples.push((Vec2::new(px as f32, py as f32) + u, l));
            }
        }
    }
    full.add_samples(&samples[..50]);
    full.add_samples(&samples[50..]);
    counted.add_samples(&samples[..50]);
    counted.add_samples(&samples[50..]);
    for &(p, l) in &samples {
        one_by_one.add_sample(p, l);
    }
    assert_eq!(full.pixels(), counted.pixels());
    assert_eq!(full.weighted_sums(), counted.weighted_sums());
    assert_eq!(full.pixel_counts(), counted.pixel_counts());
    assert_eq!(counted.pixel_counts(), one_by_one.pixel_counts());
    let counts: Vec<u32> = full.pixel_stats().iter().map(|p| p.count).collect();
    assert_eq!(&counts[..], &counted.pixel_counts()[..]);
    assert!(counts.iter().any(|&n| n > 1), "{counts:?}");
    let stats = counted.pixel_stats();
    assert!(stats.iter().zip(&counts).all(|(p, &n)| p.count == n
        && p.mean() == Spectrum::ZERO
        && p.variance_of_mean() == Spectrum::ZERO));
    // Split into two streams, each stream's film keeps its statistics again.
    let mut split = Film::new(
        FilmSettings::with_resolution(2, 1),
        &BoxFilter::new(0.5, 0.5),
    );
    split.count_only();
    split.split_streams(0.5);
    assert!(split.keeps_moments());
    split.add_stream_samples(0, &[(Vec2::new(0.5, 0.5), Spectrum::splat(2.0))]);
    split.add_stream_samples(1, &[(Vec2::new(0.5, 0.5), Spectrum::splat(4.0))]);
    assert_eq!(split.pixel_stats()[0].mean(), Spectrum::splat(3.0));
}

#[test]
fn wide_filter_reaches_neighbours_and_crop_limits_output() {
    let mut s = FilmSettings::with_resolution(4, 4);
    s.crop = [1, 3, 1, 3];
    let mut f = Film::new(s, &GaussianFilter::new(2.0, 2.0, 2.0));
    f.add_sample(Vec2::new(1.5, 1.5), Spectrum::new(1.0, 2.0, 3.0));
    let p = f.pixels();
    assert_eq!(p.len(), 4);
    for v in p {
        assert!((v - Spectrum::new(1.0, 2.0, 3.0)).length() < 1e-6);
    }
}

/// The crop window's edges are pbrt-v3's: the ceiling of resolution x fraction computed in
/// f32 (its `Float`), so 0.6 of 800 is pixel 481 (0.6f x 800 = 480.00002), as pbrt-v3's crop
/// of that window is 161 pixels wide; exact products stay exact.
#[test]
fn crop_window_edges_round_as_pbrt_v3_computes_them() {
    let mut s = FilmSettings::with_resolution(800, 400);
    s.set_crop_window([0.4, 0.6, 0.4, 0.6]).unwrap();
    assert_eq!(s.crop, [320, 481, 160, 241]);
    s.set_crop_window([0.25, 0.5, 0.0, 1.0]).unwrap();
    assert_eq!(s.crop, [200, 400, 0, 400]);
}

/// A film with half buffers keeps no splats nor statistics of its own, and gives from its
/// halves what a plain film gives: the counts exactly, the means, variances, image and sums
/// to f32 rounding; releasing its sums keeps the statistics.
#[test]
fn a_film_with_half_buffers_reads_everything_from_them() {
    use crate::first_hit::FEATURES;
    use crate::space::SamplePoint;
    let settings = FilmSettings::with_resolution(3, 2);
    let mut plain = Film::new(settings.clone(), &BoxFilter::new(0.5, 0.5));
    let mut halves = Film::new(settings, &BoxFilter::new(0.5, 0.5));
    halves.keep_pixel_buffers();
    assert!(halves.sums.is_empty() && halves.stats.is_empty());
    let (mut batch, mut radiance, mut valid) = (Vec::new(), Vec::new(), Vec::new());
    for y in 0..2u32 {
        for x in 0..3u32 {
            // Pixel (2, 1) gets no sample, pixel (0, 0) one, the others 2 to 7.
            let n = if (x, y) == (2, 1) {
                0
            } else {
                (x + 3 * y) * 2 % 7 + 1
            };
            for i in 0..n {
                let p = [x as f32 + 0.3 + 0.05 * i as f32, y as f32 + 0.6];
                let v = 0.1 + ((i * 37 + x * 11 + y * 5) % 13) as f32 * 0.7;
                batch.push(SamplePoint {
                    index: i,
                    film: p,
                    pixel: [x, y],
                    ..SamplePoint::UNMADE
                });
                radiance.push([v, 2.0 * v, 0.5]);
                valid.push((Vec2::from(p), Spectrum::new(v, 2.0 * v, 0.5)));
            }
        }
    }
    let features = vec![[0.5; FEATURES]; batch.len()];
    for f in [&mut plain, &mut halves] {
        f.add_points(&batch, &radiance, Some(&features));
        f.add_samples(&valid);
    }
    assert!(halves.sums.is_empty() && halves.stats.is_empty());
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-5 * a.abs().max(1.0);
    let (a, b) = (plain.pixel_stats(), halves.pixel_stats());
    for (p, q) in a.iter().zip(b.iter()) {
        assert_eq!(p.count, q.count);
        for (u, v) in [
            (p.mean(), q.mean()),
            (p.variance_of_mean(), q.variance_of_mean()),
        ] {
            assert!(
                close(u.x, v.x) && close(u.y, v.y) && close(u.z, v.z),
                "{u:?} {v:?}"
            );
        }
    }
    assert_eq!(b[0].count, 1);
    assert_eq!(b[5].count, 0);
    for (u, v) in plain.pixels().iter().zip(&halves.pixels()) {
        assert!(
            close(u.x, v.x) && close(u.y, v.y) && close(u.z, v.z),
            "{u:?} {v:?}"
        );
    }
    let (sa, sb) = (
        plain.weighted_sums().expect("sums"),
        halves.weighted_sums().expect("sums"),
    );
    for (u, v) in sa.iter().zip(sb.iter()) {
        assert_eq!(u[3], v[3]);
        for c in 0..3 {
            assert!(
                (u[c] - v[c]).abs() <= 1e-5 * u[c].abs().max(1.0),
                "{u:?} {v:?}"
            );
        }
    }
    let before = halves.pixel_stats().to_vec();
    halves.release_sums();
    assert!(halves.pixel_buffers().is_none());
    assert_eq!(halves.pixel_stats(), &before[..]);
}

#[test]
fn unfiltered_splats_land_in_their_pixel_scaled_and_crop_drops_the_rest() {
    let mut settings = FilmSettings::with_resolution(4, 4);
    settings.set_pixel_bounds([1, 3, 1, 3]).unwrap();
    let mut f = Film::new(settings, &BoxFilter::new(0.5, 0.5));
    f.add_splats(&[
        (Vec2::new(1.5, 2.2), Spectrum::splat(2.0)),
        (Vec2::new(1.9, 2.9), Spectrum::splat(1.0)),
        // Outside the crop, and not finite: neither lands.
        (Vec2::new(0.5, 0.5), Spectrum::splat(5.0)),
        (Vec2::new(2.5, 1.5), Spectrum::splat(f32::NAN)),
    ]);
    assert_eq!(f.unfiltered().dropped, 1);
    f.unfiltered_mut().set_scale(0.5);
    let image = f.with_splats(vec![Spectrum::ZERO; 4]);
    // Crop row 1 (raster y 2), column 0 (raster x 1): (2 + 1) * 0.5.
    assert_eq!(image[2], Spectrum::splat(1.5));
    assert_eq!(image[0], Spectrum::ZERO);
    assert_eq!(image[1], Spectrum::ZERO);
}
