//! What the plugin tests share.

use acr_plugins::space::RenderingSpace;
use acr_plugins::{Choice, Sampler, SamplerSetup, SAMPLERS};

/// The sampler `name` on `space` at `spp`, built through the registry as the command line's
/// `--spp` does.
pub fn sampler(name: &str, space: RenderingSpace, spp: u32, seed: u64) -> Box<dyn Sampler> {
    let e = SAMPLERS
        .iter()
        .find(|e| e.info.name == name)
        .unwrap_or_else(|| panic!("no sampler {name}"));
    let setup = SamplerSetup {
        space,
        spp: Some(spp),
        seed,
        reconstruction_reads_cells: true,
    };
    (e.build)(&Choice::new(None, name, None), &setup).unwrap()
}
