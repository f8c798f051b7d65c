//! acr-parser: reads pbrt-v3 scene files into a [`SceneDescription`], the scene graph that the
//! renderer builds from. Text -> tokens ([`lexer`]) -> directives ([`parser`]) -> graphics state
//! ([`builder`]) -> [`SceneDescription`]. No rendering happens here.

pub mod builder;
mod dump;
pub mod error;
pub mod lexer;
pub mod mesh;
pub mod params;
pub mod parser;
pub mod paths;
pub mod ply;
pub mod scene;
pub mod source;
pub mod suggest;
pub mod transform;

pub use error::{Error, Result, Warning};
pub use mesh::Mesh;
pub use params::{Param, ParamList, ParamType, TextureRef, Values};
pub use parser::{parse_file, parse_str};
pub use paths::{io_message, resolve_path};
pub use scene::{
    CameraDesc, InstanceDesc, LightDesc, MaterialDesc, MediumDesc, MediumInterfaceDesc, ObjectDesc,
    PluginDesc, SceneDescription, ShapeDesc, TextureDesc, TextureValue,
};
pub use source::{Loc, SourceFile};
pub use suggest::closest;
pub use transform::AnimatedTransform;

/// A number for the scene dump: short, stable, and free of floating-point dust.
pub fn fmt_num(x: f64) -> String {
    if x == 0.0 {
        return "0".to_owned();
    }
    let a = x.abs();
    if (1e-4..1e15).contains(&a) {
        // 10 significant digits, trailing zeros dropped.
        let decimals = (9 - a.log10().floor() as i32).clamp(0, 13) as usize;
        let s = format!("{x:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            s
        };
        if s == "-0" {
            "0".to_owned()
        } else {
            s
        }
    } else {
        let s = format!("{x:.9e}");
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::fmt_num;

    #[test]
    fn numbers_print_short() {
        assert_eq!(fmt_num(0.5), "0.5");
        assert_eq!(fmt_num(-0.0), "0");
        assert_eq!(fmt_num(39.14625166082039), "39.14625166");
        assert_eq!(fmt_num(1000.0), "1000");
        assert_eq!(fmt_num(7.549790126404332e-8), "7.549790126e-8");
        assert_eq!(fmt_num(2.5e20), "2.5e20");
    }
}
