//! A run's records: one per checkpoint, with the true and the estimated error, and what the
//! table and the chart make of them (the median over seeds, the fitted slope, the winner).

/// One checkpoint of a run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Record {
    pub run: String,
    pub integrator: String,
    pub parameters: String,
    pub seconds: f64,
    pub passes: u64,
    pub rel_mse: Option<f64>,
    pub rmse: Option<f64>,
    pub estimated_rel_mse: Option<f64>,
    pub estimated_bias_rel_mse: Option<f64>,
    pub seed: u64,
}

impl Record {
    /// The error that ranks runs: the true one where known, else the estimate.
    pub fn error(&self) -> Option<f64> {
        self.rel_mse.or(self.estimated_rel_mse)
    }
}

/// Checkpoint times, `per_decade` to a decade, ending at `total` and starting at a tenth of a
/// second (or at total / 100 for runs shorter than ten seconds).
pub fn checkpoints(total: f64, per_decade: u32) -> Vec<f64> {
    let first = (total / 100.0).min(0.1);
    let mut times = Vec::new();
    let mut j = 0;
    loop {
        let t = total * 10f64.powf(-(j as f64) / per_decade as f64);
        if t < first * 0.999 {
            break;
        }
        times.push(t);
        j += 1;
    }
    times.reverse();
    times
}

/// The median of `values` (the mean of the middle two for an even count).
pub fn median(mut values: Vec<f64>) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    (n > 0).then(|| (values[(n - 1) / 2] + values[n / 2]) / 2.0)
}

/// One run's records over its seeds (`by_seed`, one list of records each) reduced to one
/// record per checkpoint: at each checkpoint, every seed's first record at or after it, and
/// of those the median of each error, passes and time. A checkpoint some seed did not reach
/// (no pass finished yet) is left out.
pub fn median_over_seeds(by_seed: &[Vec<Record>], checkpoints: &[f64]) -> Vec<Record> {
    let mut out: Vec<Record> = Vec::new();
    for &t in checkpoints {
        let at: Vec<&Record> = by_seed
            .iter()
            .filter_map(|records| records.iter().find(|r| r.seconds >= t * 0.999))
            .collect();
        let Some(first) = at.first() else { continue };
        if at.len() < by_seed.len() {
            continue;
        }
        let of = |f: fn(&Record) -> Option<f64>| -> Option<f64> {
            let values: Option<Vec<f64>> = at.iter().map(|r| f(r)).collect();
            values.and_then(median)
        };
        let seconds = of(|r| Some(r.seconds)).unwrap_or(t);
        if out.last().is_some_and(|r| r.seconds >= seconds) {
            continue;
        }
        out.push(Record {
            seconds,
            passes: of(|r| Some(r.passes as f64)).unwrap_or(0.0).round() as u64,
            rel_mse: of(|r| r.rel_mse),
            rmse: of(|r| r.rmse),
            estimated_rel_mse: of(|r| r.estimated_rel_mse),
            estimated_bias_rel_mse: of(|r| r.estimated_bias_rel_mse),
            ..(*first).clone()
        });
    }
    out
}

/// Least-squares slope of log error against log time over the records from `from` seconds on.
pub fn fitted_slope(records: &[Record], from: f64) -> Option<f64> {
    let points: Vec<(f64, f64)> = records
        .iter()
        .filter(|r| r.seconds >= from)
        .filter_map(|r| r.error().filter(|e| *e > 0.0).map(|e| (r.seconds, e)))
        .map(|(t, e)| (t.ln(), e.ln()))
        .collect();
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The record of each run nearest to (at or after) time `t`, and the lowest error among them.
pub fn winner_at(runs: &[Vec<Record>], t: f64) -> Option<(usize, f64)> {
    runs.iter()
        .enumerate()
        .filter_map(|(i, records)| {
            records
                .iter()
                .find(|r| r.seconds >= t * 0.999)
                .and_then(Record::error)
                .map(|e| (i, e))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_are_log_spaced_and_end_at_the_total() {
        let c = checkpoints(60.0, 3);
        // 60 s down by thirds of a decade to the last one above 0.1 s: 60 10^(-8/3).
        assert_eq!(c.len(), 9);
        assert!(
            (c[0] - 60.0 * 10f64.powf(-8.0 / 3.0)).abs() < 1e-12,
            "{c:?}"
        );
        assert!((c.last().unwrap() - 60.0).abs() < 1e-9);
        assert!(
            c.windows(2)
                .all(|w| (w[1] / w[0] - 10f64.powf(1.0 / 3.0)).abs() < 1e-9)
        );
        assert!((checkpoints(2.0, 1)[0] - 0.02).abs() < 1e-12);
    }

    #[test]
    fn slopes_and_winners_follow_the_records() {
        let rec = |run: &str, t: f64, e: f64| Record {
            run: run.into(),
            integrator: run.into(),
            parameters: String::new(),
            seconds: t,
            passes: 1,
            rel_mse: Some(e),
            rmse: None,
            estimated_rel_mse: None,
            estimated_bias_rel_mse: None,
            seed: 0,
        };
        let a: Vec<Record> = [1.0, 10.0, 100.0]
            .iter()
            .map(|t| rec("a", *t, 1.0 / t))
            .collect();
        let b: Vec<Record> = [1.0, 10.0, 100.0]
            .iter()
            .map(|t| rec("b", *t, 0.1 / t.sqrt()))
            .collect();
        assert!((fitted_slope(&a, 0.0).unwrap() + 1.0).abs() < 1e-9);
        assert!((fitted_slope(&b, 0.0).unwrap() + 0.5).abs() < 1e-9);
        let all = [a, b];
        assert_eq!(winner_at(&all, 1.0).map(|w| w.0), Some(1));
        assert_eq!(winner_at(&all, 100.0).map(|w| w.0), Some(0));
    }
}
