//! The budgets of compared runs: at equal spp the manifest's, at equal time the first
//! method's seconds as a limit with the samples per pixel that fit in them.

use super::{Budgets, Mode};

/// Equal-time runs take the samples per pixel that the method's own equal-spp run says fit in
/// the first method's time, at most this many times the budget, with that time as a limit. A
/// sampler that plans from its budget (stratified's strata, the cluster sampler's stages)
/// then plans for what it will reach: given a larger budget and stopped by the clock, the
/// cluster sampler would spend the time in its first stage and never adapt.
const EQUAL_TIME_SPP_FACTOR: u32 = 4;

/// The equal-time budget: `spp` scaled by the first method's seconds over this method's own
/// at `spp`, within 1 and `EQUAL_TIME_SPP_FACTOR` x `spp`.
fn equal_time_spp(spp: u32, baseline: Option<f64>, own: Option<f64>) -> u32 {
    let cap = spp
        .saturating_mul(EQUAL_TIME_SPP_FACTOR)
        .min(crate::render::MAX_SPP);
    match (baseline, own) {
        (Some(base), Some(own)) if own > 0.0 && base > 0.0 => {
            ((f64::from(spp) * base / own).round() as u32).clamp(1, cap)
        }
        _ => cap,
    }
}

/// What a method's own equal-spp run at a budget spent: its sampling, and what comes after
/// the render's time limit (its reconstruction and an external method's command).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Spent {
    /// The render's seconds less its reconstruction's: what the time limit bounds.
    pub(super) render: f64,
    /// The seconds after the render's time limit: the reconstruction's plus an external
    /// method's command's.
    pub(super) after_limit: f64,
}

/// A compared run's spp and time limit: at equal spp the budget; at equal time the first
/// method's seconds at this budget (`baseline`, an error where it failed) less what the
/// method's reconstruction and command took in its own equal-spp run, as the render's limit,
/// with the spp that `time_limited_spp` names or that the method's own render seconds (`own`)
/// say fit. An
/// external method (`external`) without its own run cannot know its command's cost: an error.
pub(super) fn run_budget(
    mode: Mode,
    spp: u32,
    budgets: &Budgets,
    baseline: Option<f64>,
    own: Option<Spent>,
    external: bool,
) -> Result<(u32, Option<f64>), String> {
    if mode == Mode::EqualSpp {
        return Ok((spp, None));
    }
    let baseline = baseline.ok_or("the first method failed at this budget")?;
    if external && own.is_none() {
        return Err("its equal-spp run failed, so its command's time is unknown".to_owned());
    }
    let after = own.map_or(0.0, |o| o.after_limit);
    let limit = baseline - after;
    if limit <= 0.0 {
        return Err(format!(
            "its reconstruction and command took {after:.3} s, no less than the first method's \
             {baseline:.3} s: no time is left to render"
        ));
    }
    let spp = budgets
        .time_limited_spp
        .unwrap_or_else(|| equal_time_spp(spp, Some(limit), own.map(|o| o.render)));
    Ok((spp, Some(limit)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_time_budgets_scale_with_the_method_s_own_speed() {
        // Twice as fast as the first method: twice the spp; half as fast: half.
        assert_eq!(equal_time_spp(8, Some(2.0), Some(1.0)), 16);
        assert_eq!(equal_time_spp(8, Some(1.0), Some(2.0)), 4);
        // Within 1 and 4x the budget.
        assert_eq!(equal_time_spp(8, Some(100.0), Some(1.0)), 32);
        assert_eq!(equal_time_spp(8, Some(0.01), Some(1.0)), 1);
        // No timing to go by: the cap, and the time limit decides.
        assert_eq!(equal_time_spp(8, Some(1.0), None), 32);
    }

    #[test]
    fn a_compared_run_takes_its_budget_or_the_first_method_s_time() {
        let mut budgets = Budgets {
            spp: vec![8],
            equal_time: true,
            time_limited_spp: None,
        };
        let spent = |render, after_limit| {
            Some(Spent {
                render,
                after_limit,
            })
        };
        let run = |mode, base, own, b: &Budgets| run_budget(mode, 8, b, base, own, false);
        assert_eq!(
            run(Mode::EqualSpp, Some(1.0), None, &budgets),
            Ok((8, None))
        );
        // Twice as slow as the first method: half the spp, in its time.
        let half = spent(2.0, 0.0);
        assert_eq!(
            run(Mode::EqualTime, Some(1.0), half, &budgets),
            Ok((4, Some(1.0)))
        );
        assert!(run(Mode::EqualTime, None, spent(2.0, 0.0), &budgets)
            .is_err_and(|e| e.contains("first method failed")));
        budgets.time_limited_spp = Some(64);
        assert_eq!(
            run(Mode::EqualTime, Some(1.0), half, &budgets),
            Ok((64, Some(1.0)))
        );
        budgets.time_limited_spp = None;
        // An external method: its command's seconds come off the render's limit, and the spp
        // fit the render's share.
        let external = |base, own| run_budget(Mode::EqualTime, 8, &budgets, base, own, true);
        let (spp, limit) = external(Some(2.0), spent(1.0, 0.5)).unwrap();
        assert_eq!(spp, 12);
        assert!((limit.unwrap() - 1.5).abs() < 1e-12);
        assert!(external(Some(2.0), spent(1.0, 2.0)).is_err_and(|e| e.contains("no time")));
        assert!(external(Some(2.0), None).is_err_and(|e| e.contains("unknown")));
    }
}
