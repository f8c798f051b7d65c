//! What a render's EXR carries beside R, G, B (docs/cli.md, docs/farm.md): AOVs as channels with
//! pbrt-v4's GBuffer names (`--aov albedo,normal,depth,variance,spp` without files), mergeable
//! files with their variance moments, and the image streamed to a tev viewer (`--display-server`),
//! checked against a stand-in for tev that decodes its protocol.

mod common;

use acr::exr_channels::Channels;
use acr::image_io::read_image;
use common::{acr, ok, s, scene, temp_dir};
use std::io::Read;
use std::path::Path;

/// Channel `name` of `layer`, or a failure naming what the file has.
fn channel<'a>(layer: &'a Channels, name: &str) -> &'a [f32] {
    layer.get(name).unwrap_or_else(|| {
        let names: Vec<_> = layer.channels.iter().map(|(n, _)| n.as_str()).collect();
        panic!("no channel {name} among {names:?}")
    })
}

/// The AOVs asked for without a file land in the output EXR under pbrt-v4's names, with the
/// same values as the AOV files of the same render; the image channels are the plain render's.
#[test]
fn aovs_become_channels_of_the_output_exr() {
    let dir = temp_dir("aovs");
    let sc = scene();
    let (inside, plain) = (dir.join("inside.exr"), dir.join("plain.exr"));
    let files =
        ["albedo", "normal", "depth", "spp", "variance"].map(|n| dir.join(format!("{n}.exr")));
    let common = ["--spp", "8", "--sampler", "random", "-q"];
    let mut args = vec!["render", s(&sc), "-o", s(&inside)];
    args.extend(common);
    args.extend(["--aov", "albedo,normal,depth,spp,variance"]);
    ok(&args);
    let spec = format!(
        "albedo={},normal={},depth={},spp={},variance={}",
        s(&files[0]),
        s(&files[1]),
        s(&files[2]),
        s(&files[3]),
        s(&files[4])
    );
    let mut args = vec!["render", s(&sc), "-o", s(&plain)];
    args.extend(common);
    args.extend(["--aov", &spec]);
    ok(&args);
    let layer = Channels::read(&inside).unwrap();
    let image = read_image(&plain, false).unwrap();
    let n = image.pixels.len();
    assert_eq!(layer.width * layer.height, n);
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let v = channel(&layer, name);
        assert!((0..n).all(|i| v[i] == image.pixels[i][c]), "{name}");
    }
    let read = |p: &Path| read_image(p, false).unwrap().pixels;
    let (albedo, normal, depth, spp, var_of_mean) = (
        read(&files[0]),
        read(&files[1]),
        read(&files[2]),
        read(&files[3]),
        read(&files[4]),
    );
    for (c, rgb) in ["R", "G", "B"].into_iter().enumerate() {
        let a = channel(&layer, &format!("Albedo.{rgb}"));
        assert!((0..n).all(|i| a[i] == albedo[i][c]), "Albedo.{rgb}");
        // pbrt-v4's Variance is the variance of the pixel's samples: n times that of the mean.
        let v = channel(&layer, &format!("Variance.{rgb}"));
        assert!(
            (0..n).all(
                |i| (v[i] - var_of_mean[i][c] * spp[i][0]).abs() <= 1e-5 * v[i].abs().max(1e-6)
            ),
            "Variance.{rgb}"
        );
    }
    for (c, xyz) in ["X", "Y", "Z"].into_iter().enumerate() {
        let v = channel(&layer, &format!("Ns.{xyz}"));
        assert!((0..n).all(|i| v[i] == normal[i][c]), "Ns.{xyz}");
    }
    let z = channel(&layer, "Z");
    assert!((0..n).all(|i| z[i] == depth[i][0]));
    assert!(z.iter().any(|&d| d > 0.0), "some pixel sees a surface");
    let count = channel(&layer, "count");
    assert!(count.iter().all(|&c| c == 8.0));

    // A PNG output has no channels to hold them; an AOV that is a picture has no channel.
    let png = dir.join("x.png");
    let o = acr(&["render", s(&sc), "-o", s(&png), "--aov", "albedo", "-q"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("only when it is an .exr"),
        "{err}"
    );
    let o = acr(&[
        "render",
        s(&sc),
        "-o",
        s(&inside),
        "--aov",
        "clusters",
        "-q",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("file of its own"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A mergeable file carries the AOV channels beside its sums, and its Variance channel is the
/// plain render's.
#[test]
fn mergeable_files_carry_moments_variance_and_aovs() {
    let dir = temp_dir("moments");
    let sc = scene();
    let (m, plain) = (dir.join("m.exr"), dir.join("plain.exr"));
    let common = [
        "--spp",
        "8",
        "--sampler",
        "sobol",
        "-q",
        "--aov",
        "albedo,variance",
    ];
    let mut args = vec!["render", s(&sc), "-o", s(&m), "--mergeable"];
    args.extend(common);
    ok(&args);
    let mut args = vec!["render", s(&sc), "-o", s(&plain)];
    args.extend(common);
    ok(&args);
    let (a, b) = (Channels::read(&m).unwrap(), Channels::read(&plain).unwrap());
    for name in [
        "moment1.R",
        "moment2.B",
        "sum.G",
        "weight",
        "count",
        "Albedo.G",
    ] {
        channel(&a, name);
    }
    for name in ["Variance.R", "Variance.G", "Variance.B", "Albedo.R", "R"] {
        let (x, y) = (channel(&a, name), channel(&b, name));
        let worst = x
            .iter()
            .zip(y)
            .map(|(p, q)| (p - q).abs() / q.abs().max(1e-3))
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-4, "{name}: {worst}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A stand-in for tev: decodes the packets of tev's protocol (a little-endian u32 length, a
/// type byte, then fields) and paints the updates into an image.
struct FakeTev {
    name: String,
    width: usize,
    height: usize,
    pixels: Vec<[f32; 3]>,
    updates: usize,
}

impl FakeTev {
    fn decode(bytes: &[u8]) -> FakeTev {
        let mut tev = FakeTev {
            name: String::new(),
            width: 0,
            height: 0,
            pixels: Vec::new(),
            updates: 0,
        };
        let mut at = 0;
        while at < bytes.len() {
            let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
            let packet = &bytes[at + 4..at + len];
            at += len;
            let mut r = Reader { b: packet, at: 1 };
            match packet[0] {
                4 => {
                    let _grab = r.byte();
                    tev.name = r.string();
                    tev.width = r.u32() as usize;
                    tev.height = r.u32() as usize;
                    let n = r.u32();
                    let names: Vec<String> = (0..n).map(|_| r.string()).collect();
                    assert_eq!(names, ["R", "G", "B"]);
                    tev.pixels = vec![[0.0; 3]; tev.width * tev.height];
                }
                6 => {
                    let _grab = r.byte();
                    assert_eq!(r.string(), tev.name);
                    let n = r.u32() as usize;
                    let names: Vec<String> = (0..n).map(|_| r.string()).collect();
                    let (x, y, w, h) = (r.u32(), r.u32(), r.u32() as usize, r.u32() as usize);
                    let offsets: Vec<u64> = (0..n).map(|_| r.u64()).collect();
                    let strides: Vec<u64> = (0..n).map(|_| r.u64()).collect();
                    let data: Vec<f32> = (0..(packet.len() - r.at) / 4).map(|_| r.f32()).collect();
                    for (c, name) in names.iter().enumerate() {
                        let ch = ["R", "G", "B"].iter().position(|k| k == name).unwrap();
                        for i in 0..w * h {
                            let (px, py) = (x as usize + i % w, y as usize + i / w);
                            let v = data[(offsets[c] + i as u64 * strides[c]) as usize];
                            tev.pixels[py * tev.width + px][ch] = v;
                        }
                    }
                    tev.updates += 1;
                }
                t => panic!("unexpected packet type {t}"),
            }
        }
        tev
    }
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        self.at += n;
        &self.b[self.at - n..self.at]
    }
    fn byte(&mut self) -> u8 {
        self.take(1)[0]
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take(8).try_into().unwrap())
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take(4).try_into().unwrap())
    }
    fn string(&mut self) -> String {
        let end = self.b[self.at..].iter().position(|&c| c == 0).unwrap();
        let s = String::from_utf8(self.take(end).to_vec()).unwrap();
        self.at += 1;
        s
    }
}

/// `--display-server` creates the image in tev and sends updates; the last state tev shows is
/// the image written to the file.
#[test]
fn display_server_streams_the_image_to_tev() {
    let dir = temp_dir("tev");
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let address = listener.local_addr().unwrap().to_string();
    let server = std::thread::spawn(move || {
        let (mut stream, _) = listener.accept().unwrap();
        let mut bytes = Vec::new();
        stream.read_to_end(&mut bytes).unwrap();
        bytes
    });
    let out = dir.join("shown.exr");
    let sc = scene();
    ok(&[
        "render",
        s(&sc),
        "-o",
        s(&out),
        "--spp",
        "4",
        "-q",
        "--display-server",
        &address,
    ]);
    let tev = FakeTev::decode(&server.join().unwrap());
    let image = read_image(&out, false).unwrap();
    assert_eq!(tev.name, "shown.exr");
    assert_eq!((tev.width, tev.height), (image.width, image.height));
    assert!(tev.updates >= 1);
    assert!(tev
        .pixels
        .iter()
        .zip(&image.pixels)
        .all(|(t, p)| t[0] == p.x && t[1] == p.y && t[2] == p.z));

    // No viewer listening: a warning, and the render still done.
    let closed = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let gone = closed.local_addr().unwrap().to_string();
    drop(closed);
    let err = ok(&[
        "render",
        s(&sc),
        "-o",
        s(&out),
        "--spp",
        "1",
        "-q",
        "--display-server",
        &gone,
    ]);
    assert!(err.contains("cannot reach tev"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
