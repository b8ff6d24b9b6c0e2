//! How many photons a pass traces when the user leaves it to the photon mapper (amcppm's
//! `photons = 0`): the count that makes a pass's variance per unit of work smallest.
//!
//! A pass's estimate is the eye pass's work (its hit points, their direct light) plus the
//! photons'. With P photons a pass, its variance (relative, summed over the image) is
//! V_e + a / P and its cost c_e + b P, so the error after a given time, proportional to their
//! product, is least at P* = sqrt(a c_e / (V_e b)) (the optimal split of samples between two
//! independent parts of an estimate, as Veach 1997, section 9.2.2, does for MIS's sample
//! counts). With the current P, a = V_p P and b = c_p / P, so P* = P sqrt(V_p c_e / (V_e c_p)).
//! V_p, the photons' share, is the spread of the photon workers' parts of each hit point's
//! flux (`Gathered::tau_sq`): independent parts, so it holds the correlation of a Markov
//! chain's photons, which the sum of the photons' squared contributions (the fallback with one
//! worker) leaves out; on the door that sum made the count fall to its floor and the error
//! rise sevenfold (one seed, 20 s). V_e is the rest of the pass's variance, measured as its spread about the
//! pixel's running mean: the direct light, and the hit points' positions, which more photons
//! do not average (the door's lit gap, a pixel wide, is a matter of where each pass's hit
//! point falls). The costs are the rays each part traces (a count, so a seed makes the same
//! image on any machine with the same number of threads).
//!
//! The rule leaves out the kernel bias, and the count never rises above one photon per
//! pixel: more photons a pass are fewer passes, and SPPM's radii shrink by a ratio per pass
//! in which a photon landing counts, not how many. Uncapped, the Cornell box (whose error at
//! 30 s is mostly bias) took more photons and lost a fifth; counting the squared bias as
//! camera-side variance (gamma n B^2 a pass, from B^2 ~ n^(-gamma), gamma = 2 (1 - alpha),
//! which holds only where photons land every pass) sent the door's count to its floor and
//! its error up fourfold (DESIGN.md 5b).
//!
//! Where photons bring little (the material spheres, lit directly by the studio) this spends
//! the pass on camera paths; where the image is mostly photons (a caustic) it keeps one per
//! pixel. The count moves by at most a quarter a photon pass and stays within a sixty-fourth
//! of one photon per pixel and one.
//!
//! Below an eighth of a photon per pixel the count is an average (`PhotonSchedule`): passes
//! without photons save their share up for one that traces at least that eighth. A photon
//! pass has costs that do not shrink with its count (amcppm's chains search a few hundred
//! paths for their first visible state, the grid is built over every hit point, every pixel
//! is updated): on the material spheres they were a third of a pass at the eighth (DESIGN.md
//! 5b), and spent every few passes they are a few percent. The rule above holds for the
//! average: over n passes the photons' variance is a / (n P) whether P photons are traced
//! every pass or k P every k-th, and their rays b P a pass either way, with a and b measured
//! on the photon passes. The error estimate weighs a photon pass for the passes it stands for
//! (`error.rs`).

use crate::error_estimate::REL_MSE_EPSILON;

/// Passes before the count first moves: the running means the variances are measured
/// against need a few passes.
const FIRST_ADAPTIVE_PASS: u64 = 8;
/// Weight of the newest pass in the running variances.
const SMOOTHING: f64 = 0.1;
/// The most the count changes in one pass (a factor).
const MAX_STEP: f64 = 1.25;

/// The running variances of a pass's two parts and the rule that turns them into a count.
#[derive(Clone, Debug, Default)]
pub(super) struct PhotonBudget {
    eye_variance: f64,
    photon_variance: f64,
    observed: u64,
}

/// One pixel of a finished pass: this pass's estimate (luminance), the mean of the passes
/// before it, and the photons' variance in it.
pub(super) struct PixelPass {
    pub estimate: f64,
    pub mean: f64,
    pub photon_variance: f64,
}

/// The eye part's least share of a pass's variance: the difference of two estimates is noisy,
/// and a pass is never all photons (its hit points move).
const EYE_FLOOR: f64 = 0.05;

impl PhotonBudget {
    /// Adds a pass's pixels (after at least one earlier pass), each relative to the pixel's
    /// value as relMSE weighs it.
    pub(super) fn observe(&mut self, pixels: impl Iterator<Item = PixelPass>) {
        let (mut total, mut photon) = (0.0, 0.0);
        for p in pixels {
            let weight = 1.0 / (p.mean * p.mean + REL_MSE_EPSILON);
            total += weight * (p.estimate - p.mean).powi(2);
            photon += weight * p.photon_variance;
        }
        if !(total.is_finite() && photon.is_finite()) {
            return;
        }
        let eye = (total - photon).max(EYE_FLOOR * total);
        let s = if self.observed == 0 { 1.0 } else { SMOOTHING };
        self.eye_variance += s * (eye - self.eye_variance);
        self.photon_variance += s * (photon - self.photon_variance);
        self.observed += 1;
    }

    /// The next average count from the current one (`average`), the count of the photon pass
    /// just traced (`photons`: the average, or the several passes' worth it saved up), the
    /// rays its eye and photon parts traced, and the allowed `range` (module docs).
    pub(super) fn next(
        &self,
        average: u64,
        photons: u64,
        eye_rays: u64,
        photon_rays: u64,
        passes: u64,
        range: (u64, u64),
    ) -> u64 {
        if passes < FIRST_ADAPTIVE_PASS || self.observed == 0 {
            return average.clamp(range.0, range.1);
        }
        let ratio =
            (self.photon_variance * eye_rays as f64) / (self.eye_variance * photon_rays as f64);
        let wanted = if ratio.is_nan() {
            average as f64
        } else {
            photons as f64 * ratio.sqrt()
        };
        let average = average as f64;
        let next = wanted.clamp(average / MAX_STEP, average * MAX_STEP);
        (next.round() as u64).clamp(range.0, range.1)
    }
}

/// The range the average count moves in, from the first pass's count (`photons_per_pass`: one
/// per pixel within 10^4 and 10^6): a sixty-fourth of it to it (module docs).
pub(super) fn photon_range(first: u64) -> (u64, u64) {
    ((first / 64).max(1), first)
}

/// The fewest photons a photon pass traces: an eighth of the first pass's count (module docs).
pub(super) fn photon_pass_floor(first: u64) -> u64 {
    (first / 8).max(1)
}

/// Which passes trace photons (module docs): every pass while the average count is at least a
/// photon pass's floor; below it, a pass adds the average to what the passes before it saved,
/// and traces them once they reach the floor.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PhotonSchedule {
    saved: u64,
    passes: u64,
}

impl PhotonSchedule {
    /// This pass's photons and the passes they stand for (this one and those before it that
    /// traced none), or None for a pass without photons.
    pub(super) fn next(&mut self, average: u64, floor: u64) -> Option<(u64, u64)> {
        self.saved += average;
        self.passes += 1;
        if self.saved < floor {
            return None;
        }
        let pass = (self.saved, self.passes);
        *self = PhotonSchedule::default();
        Some(pass)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pass of 100 pixels of mean 1 whose estimates spread by `spread` about it, of which
    /// the photons' variance is `photon_variance`.
    fn pass(budget: &mut PhotonBudget, spread: f64, photon_variance: f64) {
        budget.observe((0..100).map(|i| PixelPass {
            estimate: 1.0 + if i % 2 == 0 { spread } else { -spread },
            mean: 1.0,
            photon_variance,
        }));
    }

    /// The count follows sqrt(V_p c_e / (V_e c_p)) within its step and range.
    #[test]
    fn the_count_follows_the_optimal_split() {
        let range = (1_000, 1_000_000);
        // Photons four fifths of the variance (four times the eye's), at equal cost: double,
        // a step at a time.
        let mut budget = PhotonBudget::default();
        pass(&mut budget, 0.1, 0.008);
        assert_eq!(
            budget.next(10_000, 10_000, 100, 100, 4, range),
            10_000,
            "too early"
        );
        assert_eq!(
            budget.next(10_000, 10_000, 100, 100, 8, range),
            12_500,
            "one step"
        );
        // Half the variance, photons four times as costly: halve, a step at a time.
        let mut budget = PhotonBudget::default();
        pass(&mut budget, 0.1, 0.005);
        assert_eq!(budget.next(10_000, 10_000, 100, 400, 8, range), 8_000);
        // At the optimum it stays: variance ratio 4, cost ratio 4.
        let mut budget = PhotonBudget::default();
        pass(&mut budget, 0.1, 0.008);
        assert_eq!(budget.next(10_000, 10_000, 100, 400, 8, range), 10_000);
        // No photons in the variance: down to the range's floor, never to zero.
        let mut budget = PhotonBudget::default();
        pass(&mut budget, 0.1, 0.0);
        assert_eq!(budget.next(1_100, 1_100, 100, 100, 8, range), 1_000);
        // All of it photons: the eye keeps its floor (ratio 19), so up, within the range.
        let mut budget = PhotonBudget::default();
        pass(&mut budget, 0.1, 0.01);
        assert_eq!(budget.next(900_000, 900_000, 100, 100, 8, range), 1_000_000);
        // Nothing measured yet (both zero): no change.
        let mut budget = PhotonBudget::default();
        pass(&mut budget, 0.0, 0.0);
        assert_eq!(budget.next(5_000, 5_000, 100, 100, 8, range), 5_000);
        // An average of 1,000 traced as 4,000 every fourth pass, whose variance and rays were
        // measured at 4,000: half the variance, photons 64 times as costly, so the optimum is
        // 4,000 sqrt(1 / 64) = 500, half the average, which is approached a step at a time.
        let mut budget = PhotonBudget::default();
        pass(&mut budget, 0.1, 0.005);
        assert_eq!(budget.next(1_000, 4_000, 100, 6_400, 8, (1, 10_000)), 800);
        // From below: 4,000 sqrt(4) = 8,000, eight times the average: a step up.
        let mut budget = PhotonBudget::default();
        pass(&mut budget, 0.1, 0.008);
        assert_eq!(budget.next(1_000, 4_000, 100, 100, 8, (1, 10_000)), 1_250);
    }

    /// At or above the floor every pass traces the average; below it the passes save up, and
    /// over many passes the photons traced are the averages' sum (to within one pass's worth).
    #[test]
    fn the_schedule_saves_photons_up_to_the_floor() {
        let mut schedule = PhotonSchedule::default();
        for average in [1_000, 5_000] {
            assert_eq!(schedule.next(average, 1_000), Some((average, 1)));
        }
        // 300 a pass against a floor of 1,000: every fourth pass traces the 1,200 the four
        // saved: every pass's photons are traced, none twice.
        let (mut traced, mut passes_counted, mut photon_passes) = (0, 0, 0);
        let mut pattern = Vec::new();
        for _ in 0..1_000 {
            if let Some((photons, passes)) = schedule.next(300, 1_000) {
                assert_eq!(photons, 300 * passes, "what the passes saved");
                traced += photons;
                passes_counted += passes;
                photon_passes += 1;
                pattern.push(passes);
            }
        }
        assert!(pattern.iter().all(|&p| p == 4), "{pattern:?}");
        assert_eq!(photon_passes, 250);
        assert_eq!((traced, passes_counted), (300_000, 1_000));
    }
}
