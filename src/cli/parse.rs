//! `acr parse`: the scene graph as the snapshot tests see it.

use std::io::Write;
use std::path::Path;

/// Parses `scene` and prints its description.
pub fn command(scene: &Path) -> Result<(), String> {
    let desc = acr_parser::parse_file(scene).map_err(|e| e.to_string())?;
    let mut out = std::io::stdout().lock();
    // A closed pipe (acr parse x | head) is not an error worth reporting.
    let _ = out.write_all(desc.to_text().as_bytes());
    Ok(())
}
