//! `acr diff`: an image against a reference.

use std::path::Path;

/// Prints MSE, relMSE, PSNR and the means of `image` against `reference`.
pub fn command(image: &Path, reference: &Path, json: bool) -> Result<(), String> {
    let read = |p: &Path| {
        crate::image_io::read_image(p, true).map_err(|e| format!("{}: {e}", p.display()))
    };
    let (a, b) = (read(image)?, read(reference)?);
    let m = crate::metrics::compare(&a, &b)
        .map_err(|e| format!("{} vs {}: {e}", image.display(), reference.display()))?;
    if json {
        let text = serde_json::to_string(&m).map_err(|e| e.to_string())?;
        println!("{text}");
    } else {
        println!(
            "mse {:.6e}  relmse {:.6e}  psnr {:.3} dB  mean {:.6} (reference {:.6})",
            m.mse, m.relmse, m.psnr, m.mean, m.reference_mean
        );
    }
    Ok(())
}
