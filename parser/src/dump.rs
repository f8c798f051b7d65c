//! The scene graph as stable, readable text: what `acr parse` prints and snapshots compare.

use crate::fmt_num;
use crate::scene::{MediumInterfaceDesc, PluginDesc, SceneDescription, ShapeDesc};
use crate::source::Loc;
use crate::transform::AnimatedTransform;
use glam::DMat4;
use std::fmt::Write;
use std::path::Path;

/// Matrix entries this small are floating-point dust from rotations and inverses.
const DUST: f64 = 1e-12;

fn matrix(m: &DMat4) -> String {
    if m.abs_diff_eq(DMat4::IDENTITY, DUST) {
        return "identity".to_owned();
    }
    let rows: Vec<String> = (0..4)
        .map(|r| {
            let row = m.row(r);
            let v: Vec<String> = row
                .to_array()
                .iter()
                .map(|&x| fmt_num(if x.abs() < DUST { 0.0 } else { x }))
                .collect();
            format!("[{}]", v.join(" "))
        })
        .collect();
    format!("[{}]", rows.join(" "))
}

fn animated(t: &AnimatedTransform) -> String {
    if t.is_animated() {
        format!(
            "t={} {} -> t={} {}",
            fmt_num(t.start_time),
            matrix(&t.start),
            fmt_num(t.end_time),
            matrix(&t.end)
        )
    } else {
        matrix(&t.start)
    }
}

impl SceneDescription {
    /// The scene graph as text, with file names relative to the main file's directory.
    pub fn to_text(&self) -> String {
        let base = self
            .files
            .first()
            .map(|f| f.dir().to_path_buf())
            .unwrap_or_default();
        let d = Dump { base: &base };
        let mut out = String::new();
        let o = &mut out;
        let files: Vec<String> = self.files.iter().map(|f| d.path(&f.path)).collect();
        wl(o, 0, format!("files: {}", files.join(", ")));
        let (t0, t1) = self.transform_times;
        wl(
            o,
            0,
            format!("transform times: {} {}", fmt_num(t0), fmt_num(t1)),
        );
        match &self.camera {
            Some(c) => {
                d.plugin(o, 0, "camera", &c.plugin);
                wl(
                    o,
                    1,
                    format!("camera_from_world: {}", animated(&c.camera_from_world)),
                );
                d.params(o, 1, &c.plugin);
            }
            None => wl(o, 0, "camera: none"),
        }
        for (what, p) in [
            ("film", &self.film),
            ("sampler", &self.sampler),
            ("filter", &self.filter),
            ("integrator", &self.integrator),
            ("accelerator", &self.accelerator),
        ] {
            match p {
                Some(p) => {
                    d.plugin(o, 0, what, p);
                    d.params(o, 1, p);
                }
                None => wl(o, 0, format!("{what}: none")),
            }
        }
        wl(o, 0, format!("materials: {}", self.materials.len()));
        for (i, m) in self.materials.iter().enumerate() {
            let mut head = format!("#{i}");
            if let Some(n) = &m.name {
                let _ = write!(head, " \"{n}\"");
            }
            if i == 0 {
                wl(o, 1, format!("{head} {} (default)", m.plugin.kind));
                continue;
            }
            d.plugin(o, 1, &head, &m.plugin);
            if let Some([a, b]) = m.mix {
                wl(o, 2, format!("mixes materials #{a} and #{b}"));
            }
            d.params(o, 2, &m.plugin);
        }
        wl(o, 0, format!("textures: {}", self.textures.len()));
        for (i, t) in self.textures.iter().enumerate() {
            let head = format!("#{i} \"{}\" {:?}", t.name, t.value).to_lowercase();
            d.plugin(o, 1, &head, &t.plugin);
            if !t.world_from_texture.abs_diff_eq(DMat4::IDENTITY, DUST) {
                wl(
                    o,
                    2,
                    format!("world_from_texture: {}", matrix(&t.world_from_texture)),
                );
            }
            d.params(o, 2, &t.plugin);
        }
        wl(o, 0, format!("lights: {}", self.lights.len()));
        for (i, l) in self.lights.iter().enumerate() {
            d.plugin(o, 1, &format!("#{i}"), &l.plugin);
            wl(
                o,
                2,
                format!("world_from_light: {}", matrix(&l.world_from_light)),
            );
            media_line(o, 2, &l.media);
            d.params(o, 2, &l.plugin);
        }
        // Media only where the scene has them, so that other scenes' dumps stay as they were.
        if !self.media.is_empty() {
            wl(o, 0, format!("media: {}", self.media.len()));
            for (i, m) in self.media.iter().enumerate() {
                d.plugin(o, 1, &format!("#{i} \"{}\"", m.name), &m.plugin);
                if !m.world_from_medium.abs_diff_eq(DMat4::IDENTITY, DUST) {
                    let t = matrix(&m.world_from_medium);
                    wl(o, 2, format!("world_from_medium: {t}"));
                }
                d.params(o, 2, &m.plugin);
            }
            let camera = self
                .camera_medium
                .map_or("vacuum".to_owned(), |m| format!("#{m}"));
            wl(o, 0, format!("camera medium: {camera}"));
        }
        wl(o, 0, format!("shapes: {}", self.shapes.len()));
        for (i, s) in self.shapes.iter().enumerate() {
            d.shape(o, 1, i, s);
        }
        wl(o, 0, format!("objects: {}", self.objects.len()));
        for (i, (name, obj)) in self.objects.iter().enumerate() {
            wl(
                o,
                1,
                format!(
                    "#{i} \"{name}\" at {}: {} shapes",
                    d.loc(&obj.loc),
                    obj.shapes.len()
                ),
            );
            for (j, s) in obj.shapes.iter().enumerate() {
                d.shape(o, 2, j, s);
            }
        }
        wl(o, 0, format!("instances: {}", self.instances.len()));
        for (i, inst) in self.instances.iter().enumerate() {
            let name = self
                .objects
                .get_index(inst.object)
                .map_or("?", |(n, _)| n.as_str());
            wl(o, 1, format!("#{i} of \"{name}\" at {}", d.loc(&inst.loc)));
            wl(
                o,
                2,
                format!(
                    "world_from_instance: {}",
                    animated(&inst.world_from_instance)
                ),
            );
        }
        wl(o, 0, format!("warnings: {}", self.warnings.len()));
        for w in &self.warnings {
            let at = w
                .loc
                .as_ref()
                .map_or(String::new(), |l| format!("{}: ", d.loc(l)));
            wl(o, 1, format!("{at}{}", w.message));
        }
        out
    }
}

/// The media on either side, when there are any.
fn media_line(o: &mut String, indent: usize, m: &MediumInterfaceDesc) {
    if *m == MediumInterfaceDesc::default() {
        return;
    }
    let name = |m: Option<usize>| m.map_or("vacuum".to_owned(), |m| format!("#{m}"));
    let (inside, outside) = (name(m.inside), name(m.outside));
    wl(
        o,
        indent,
        format!("media: inside {inside}, outside {outside}"),
    );
}

/// Writes one indented line.
fn wl(out: &mut String, indent: usize, line: impl AsRef<str>) {
    for _ in 0..indent {
        out.push_str("  ");
    }
    out.push_str(line.as_ref());
    out.push('\n');
}

struct Dump<'a> {
    base: &'a Path,
}

impl Dump<'_> {
    fn path(&self, p: &Path) -> String {
        let rel = p.strip_prefix(self.base).unwrap_or(p);
        rel.display().to_string().replace('\\', "/")
    }

    fn loc(&self, loc: &Loc) -> String {
        let (line, col) = loc.line_col();
        format!("{}:{line}:{col}", self.path(&loc.file.path))
    }

    fn plugin(&self, o: &mut String, indent: usize, head: &str, p: &PluginDesc) {
        wl(
            o,
            indent,
            format!("{head} {} at {}", p.kind, self.loc(&p.loc)),
        );
    }

    fn params(&self, o: &mut String, indent: usize, p: &PluginDesc) {
        for param in p.params.iter() {
            wl(o, indent, param.to_string());
        }
    }

    fn shape(&self, o: &mut String, indent: usize, i: usize, s: &ShapeDesc) {
        let mut head = format!("#{i}");
        match s.material {
            Some(m) => {
                let _ = write!(head, " material #{m}");
            }
            None => head.push_str(" no material"),
        }
        if s.reverse_orientation {
            head.push_str(" reversed");
        }
        self.plugin(o, indent, &head, &s.plugin);
        wl(
            o,
            indent + 1,
            format!("world_from_object: {}", animated(&s.world_from_object)),
        );
        media_line(o, indent + 1, &s.media);
        if let Some(a) = &s.area_light {
            wl(
                o,
                indent + 1,
                format!("area light {} at {}", a.kind, self.loc(&a.loc)),
            );
            self.params(o, indent + 2, a);
        }
        if let Some(m) = &s.mesh {
            let mut line = format!(
                "mesh: {} vertices, {} triangles",
                m.positions.len(),
                m.triangle_count()
            );
            if m.normals.is_some() {
                line.push_str(", normals");
            }
            if m.uvs.is_some() {
                line.push_str(", uvs");
            }
            wl(o, indent + 1, line);
        }
        self.params(o, indent + 1, &s.plugin);
    }
}
