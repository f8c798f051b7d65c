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

/// A compared run's spp and time limit: at equal spp the budget; at equal time the first
/// method's seconds at this budget as the limit (`seconds.0`, an error where it failed) with the
/// spp that `time_limited_spp` names or the method's own equal-spp seconds (`seconds.1`) say fit.
pub(super) fn run_budget(
    mode: Mode,
    spp: u32,
    budgets: &Budgets,
    seconds: (Option<f64>, Option<f64>),
) -> Result<(u32, Option<f64>), String> {
    match (mode, seconds) {
        (Mode::EqualSpp, _) => Ok((spp, None)),
        (Mode::EqualTime, (None, _)) => Err("the first method failed at this budget".to_owned()),
        (Mode::EqualTime, (Some(baseline), own)) => Ok((
            budgets
                .time_limited_spp
                .unwrap_or_else(|| equal_time_spp(spp, Some(baseline), own)),
            Some(baseline),
        )),
    }
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
        let run = |mode, seconds, b: &Budgets| run_budget(mode, 8, b, seconds);
        assert_eq!(
            run(Mode::EqualSpp, (Some(1.0), None), &budgets),
            Ok((8, None))
        );
        // Twice as slow as the first method: half the spp, in its time.
        let half = (Some(1.0), Some(2.0));
        assert_eq!(run(Mode::EqualTime, half, &budgets), Ok((4, Some(1.0))));
        assert!(run(Mode::EqualTime, (None, Some(2.0)), &budgets)
            .is_err_and(|e| e.contains("first method failed")));
        budgets.time_limited_spp = Some(64);
        assert_eq!(run(Mode::EqualTime, half, &budgets), Ok((64, Some(1.0))));
    }
}
