//! acr-plugins: the plugin traits and registry, the samplers, the film and the reconstruction
//! filters, over the abstract rendering space. Nothing here knows about geometry, so every
//! plugin is testable on analytic integrands.

pub mod cells;
pub mod color;
pub mod film;
pub mod filters;
pub mod first_hit;
pub mod kernel;
pub mod partition;
pub mod polynomial_fit;
pub mod prefilter;
pub mod registry;
pub mod rng;
pub mod sampler;
pub mod space;

pub use film::{Film, FilmSettings, PixelStats};
pub use filters::{Filter, FilterKernel, FILTERS};
pub use partition::Partition;
pub use registry::{Choice, Entry, Kind, ParamSpec, PluginInfo, Setting};
pub use sampler::{Sampler, SamplerSetup, SAMPLERS};
pub use space::{Dims, RenderingSpace, SamplePoint};
