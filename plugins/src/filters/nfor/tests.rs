//! The whole filter on films made by hand.

use super::*;
use crate::film::FilmSettings;
use crate::first_hit::Features;
use crate::space::SamplePoint;

/// A `w` x `h` film with half buffers, `spp` samples a pixel: `sample(x, y, i)` gives each
/// sample's radiance and features (None: no sample).
fn film(
    w: u32,
    h: u32,
    spp: u32,
    sample: impl Fn(u32, u32, u32) -> Option<([f32; 3], Features)>,
) -> Film {
    let mut film = Film::new(
        FilmSettings::with_resolution(w, h),
        &BoxFilter::new(0.5, 0.5),
    );
    film.keep_pixel_buffers();
    add_rows(&mut film, w, 0..h, spp, &sample);
    film
}

/// Adds the samples of rows `rows` to `film`, as [`film`] does.
fn add_rows(
    film: &mut Film,
    w: u32,
    rows: Range<u32>,
    spp: u32,
    sample: impl Fn(u32, u32, u32) -> Option<([f32; 3], Features)>,
) {
    let (mut batch, mut radiance, mut features) = (Vec::new(), Vec::new(), Vec::new());
    for y in rows {
        for x in 0..w {
            for i in 0..spp {
                let Some((l, f)) = sample(x, y, i) else {
                    continue;
                };
                batch.push(SamplePoint {
                    pixel: [x, y],
                    index: i,
                    film: [x as f32 + 0.5, y as f32 + 0.5],
                    ..SamplePoint::UNMADE
                });
                radiance.push(l);
                features.push(f);
            }
        }
    }
    film.add_points(&batch, &radiance, Some(&features));
}

/// A wall: grey albedo, facing the camera, at depth 2.
const WALL: Features = [0.5, 0.5, 0.5, 0.0, 0.0, 1.0, 2.0];

/// A value in [0, 1) hashed from `n`.
fn hash(n: u32) -> f32 {
    let mut v = n.wrapping_mul(0x9E37_79B9) ^ 0x5bd1_e995;
    v ^= v >> 15;
    v = v.wrapping_mul(0x2c1b_3c6d);
    v ^= v >> 12;
    (v >> 8) as f32 / (1 << 24) as f32
}

fn reconstruct(f: &NforFilter, film: &Film) -> Vec<Spectrum> {
    f.reconstruct(film, SamplerOutput::default())
}

#[test]
fn a_constant_image_stays_constant() {
    let film = film(40, 30, 8, |_, _, _| Some(([0.25, 0.5, 0.75], WALL)));
    let out = reconstruct(&NforFilter::default(), &film);
    for c in out {
        assert!(
            (c.x - 0.25).abs() < 1e-5 && (c.y - 0.5).abs() < 1e-5,
            "{c:?}"
        );
        assert!((c.z - 0.75).abs() < 1e-5, "{c:?}");
    }
}

#[test]
fn a_texture_above_the_noise_keeps_the_pixel_means() {
    // A texture the features do not explain, with noise far below it: the unfiltered means
    // are the best estimate and the choice must fall on them.
    let truth = |x: u32, y: u32| hash(y * 64 + x);
    let film = film(48, 32, 8, |x, y, i| {
        let noise = if i % 2 == 0 { 0.002 } else { -0.002 } * (1.0 + (i / 2) as f32);
        let v = truth(x, y) + noise;
        Some(([v, v, v], WALL))
    });
    let means: Vec<f32> = film.pixel_stats().iter().map(|s| s.mean().x).collect();
    let out = reconstruct(&NforFilter::default(), &film);
    let mse = |img: &mut dyn Iterator<Item = f32>| {
        let mut s = 0.0f64;
        for (i, v) in img.enumerate() {
            let t = truth(i as u32 % 48, i as u32 / 48);
            s += f64::from(v - t).powi(2);
        }
        s / (48.0 * 32.0)
    };
    let raw = mse(&mut means.iter().copied());
    let filtered = mse(&mut out.iter().map(|c| c.x));
    assert!(filtered <= raw, "{filtered} vs {raw}");
}

#[test]
fn the_same_image_on_one_or_two_threads() {
    let film = film(70, 45, 6, |x, y, i| {
        let v = hash(((y * 70 + x) << 3) + i) * if x > 30 { 2.0 } else { 0.5 };
        let f = if y > 20 {
            WALL
        } else {
            [0.2, 0.8, 0.1, 0.0, 1.0, 0.0, 5.0]
        };
        Some(([v, v * 0.5, 0.1], f))
    });
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| reconstruct(&NforFilter::default(), &film))
    };
    let (a, b) = (run(1), run(2));
    let bits = |v: &[Spectrum]| -> Vec<u32> {
        v.iter()
            .flat_map(|c| [c.x.to_bits(), c.y.to_bits(), c.z.to_bits()])
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
}

#[test]
fn pixels_without_samples_or_surfaces_stay_finite() {
    // Empty pixels, pixels with one half only, and pixels that saw only an emitter.
    let film = film(33, 20, 4, |x, y, i| match (x + y) % 5 {
        0 => None,
        1 if i % 2 == 1 => None,
        2 => Some(([5.0, 5.0, 5.0], [0.0; 7])),
        _ => Some(([hash(x * 31 + y + i), 0.3, 0.2], WALL)),
    });
    let f = NforFilter::default();
    let out = reconstruct(&f, &film);
    assert!(out.iter().all(|c| c.is_finite()), "{out:?}");
    let err = f.estimated_error(&film).expect("an estimate");
    assert_eq!(err.len(), 33 * 20);
    assert!(err.iter().all(|e| e.is_finite() && *e >= 0.0));
    // An emitter's pixels are never mixed with the surfaces around them.
    for (i, c) in out.iter().enumerate() {
        let (x, y) = (i as u32 % 33, i as u32 / 33);
        if (x + y) % 5 == 2 {
            assert!((c.x - 5.0).abs() < 1e-4, "{x},{y}: {c:?}");
        }
    }
}

#[test]
fn a_splatting_film_gives_its_pixel_means() {
    // Without half buffers (a stream's own film) the filter falls back to the pixel means.
    let mut film = Film::new(
        FilmSettings::with_resolution(4, 2),
        &BoxFilter::new(0.5, 0.5),
    );
    film.add_sample(glam::Vec2::new(1.5, 0.5), Spectrum::ONE);
    let out = reconstruct(&NforFilter::default(), &film);
    assert_eq!(out[1], Spectrum::ONE);
    assert_eq!(out[0], Spectrum::ZERO);
}

/// Rows of different kinds (walls, a second surface, an emitter) and noise, `w` pixels wide.
fn striped(w: u32) -> impl Fn(u32, u32, u32) -> Option<([f32; 3], Features)> {
    move |x, y, i| {
        let v = hash(((y * w + x) << 3) + i) * if (x + y / 7) % 9 > 4 { 2.0 } else { 0.5 };
        match (y / 11) % 4 {
            0 => Some(([4.0, 4.0, 4.0], [0.0; 7])),
            1 => Some((
                [v, v * 0.5, 0.1],
                [0.2, 0.8, 0.1, 0.0, 1.0, 0.0, 5.0 + y as f32],
            )),
            _ => Some(([v, v, v * 2.0], WALL)),
        }
    }
}

/// Each channel's bits.
fn bits(v: &[Spectrum]) -> Vec<u32> {
    v.iter()
        .flat_map(|c| [c.x.to_bits(), c.y.to_bits(), c.z.to_bits()])
        .collect()
}

#[test]
fn bands_give_the_whole_images_bytes() {
    // Tall enough for five bands of 32 rows with their halo: every pixel, its estimated error
    // too, must come out as from the whole image at once.
    let (w, h) = (24, 150);
    let film = film(w, h, 4, striped(w));
    // The default windows, with and without the second pass, and wider ones (a halo of two
    // tiles).
    let wider = || NforFilter::new(5, 2, 4, 2, RIDGE);
    for (filter, second) in [
        (NforFilter::default as fn() -> NforFilter, true),
        (NforFilter::default, false),
        (wider, true),
    ] {
        let whole = filter().with_second_pass(second).with_band(0);
        let banded = filter().with_second_pass(second).with_band(1);
        let a = reconstruct(&whole, &film);
        let b = reconstruct(&banded, &film);
        assert_eq!(b.len(), (w * h) as usize);
        assert_eq!(bits(&a), bits(&b), "second pass {second}");
        let ea = whole.estimated_error(&film).expect("an estimate");
        let eb = banded.estimated_error(&film).expect("an estimate");
        let fb = |v: &[f32]| v.iter().map(|e| e.to_bits()).collect::<Vec<_>>();
        assert_eq!(fb(&ea), fb(&eb));
    }
}

#[test]
fn a_film_that_holds_a_window_of_rows_gives_the_whole_images_bytes() {
    // A render by bands: rows come in band by band, each band is made once its rows and halo
    // are in, and the rows no later band reads are freed; the depth scale is set before.
    let (w, h) = (24, 150);
    for second in [true, false] {
        let filter = NforFilter::default().with_second_pass(second).with_band(32);
        let mut whole = film(w, h, 4, striped(w));
        whole.set_depth_scale(0.25);
        let expected = reconstruct(&filter.clone().with_band(0), &whole);
        let plan = filter.bands(h as usize).expect("bands");
        let mut film = Film::new(
            FilmSettings::with_resolution(w, h),
            &BoxFilter::new(0.5, 0.5),
        );
        film.keep_pixel_buffers();
        film.set_depth_scale(0.25);
        film.hold_rows(false, plan.rows + 2 * plan.halo);
        let (mut got, mut rows_in) = (Vec::new(), 0);
        let mut most_held = 0;
        for band in plan.layout(h as usize) {
            let read = plan.read(&band, h as usize);
            add_rows(&mut film, w, rows_in as u32..read.end as u32, 4, striped(w));
            rows_in = read.end;
            let held = film.pixel_buffers().expect("buffers").held_rows();
            most_held = most_held.max(held.len());
            got.extend(filter.reconstruct_rows(&film, band.clone()));
            film.release_rows(band.end.saturating_sub(plan.halo));
        }
        assert_eq!(bits(&got), bits(&expected), "second pass {second}");
        assert!(most_held <= plan.rows + 2 * plan.halo, "{most_held}");
        // Every pixel's count is kept, and no sums (nothing to merge).
        film.release_rows(h as usize);
        assert!(film.pixel_stats().iter().all(|s| s.count == 4));
        assert!(film.weighted_sums().is_none());
        // Without a depth scale set, the halves' own: another image.
        let mut unscaled = film_of(w, h);
        assert_ne!(bits(&reconstruct(&filter, &unscaled)), bits(&expected));
        unscaled.set_depth_scale(0.25);
        assert_eq!(bits(&reconstruct(&filter, &unscaled)), bits(&expected));
    }
}

/// The striped film, whole.
fn film_of(w: u32, h: u32) -> Film {
    film(w, h, 4, striped(w))
}
