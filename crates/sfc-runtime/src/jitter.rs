//! Scan timing statistics in constant memory: a histogram of 1 µs buckets up to 100 ms (later
//! values share the last bucket; the maximum is kept exactly), and for scan times a log-linear
//! histogram in nanoseconds (64 buckets per power of two, so about 1.6 % resolution), which shows
//! scans far shorter than a microsecond.

const BUCKETS: usize = 100_000;
/// Buckets summed per block, so a quantile walks the blocks first.
const BLOCK: usize = 1024;

/// A distribution of durations in µs.
#[derive(Debug, Clone)]
pub struct Histogram {
    counts: Vec<u32>,
    /// Sums of `counts` per block of `BLOCK` buckets.
    blocks: Vec<u64>,
    n: u64,
    max: u64,
    sum: u64,
}

impl Default for Histogram {
    fn default() -> Self {
        Histogram { counts: vec![0; BUCKETS], blocks: vec![0; BUCKETS.div_ceil(BLOCK)], n: 0, max: 0, sum: 0 }
    }
}

impl Histogram {
    pub fn add(&mut self, us: u64) {
        let b = (us as usize).min(BUCKETS - 1);
        if let Some(c) = self.counts.get_mut(b) {
            *c = c.saturating_add(1);
        }
        if let Some(k) = self.blocks.get_mut(b / BLOCK) {
            *k += 1;
        }
        self.n += 1;
        self.max = self.max.max(us);
        self.sum = self.sum.saturating_add(us);
    }
    pub fn count(&self) -> u64 {
        self.n
    }
    pub fn max(&self) -> u64 {
        self.max
    }
    pub fn mean(&self) -> u64 {
        self.sum.checked_div(self.n).unwrap_or(0)
    }
    /// The smallest value with at least `q` (0..=1) of the samples at or below it.
    pub fn quantile(&self, q: f64) -> u64 {
        if self.n == 0 {
            return 0;
        }
        let want = ((q * self.n as f64).ceil() as u64).clamp(1, self.n);
        let mut seen = 0u64;
        for (k, &c) in self.blocks.iter().enumerate() {
            if seen + c < want {
                seen += c;
                continue;
            }
            let start = k * BLOCK;
            for (b, &c) in self.counts.iter().skip(start).take(BLOCK).enumerate() {
                seen += u64::from(c);
                if seen >= want {
                    let b = start + b;
                    return if b == BUCKETS - 1 { self.max } else { b as u64 };
                }
            }
        }
        self.max
    }
    /// `{"p50":…,"p99":…,"max":…,"mean":…}` in µs.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({"p50": self.quantile(0.5), "p99": self.quantile(0.99), "max": self.max, "mean": self.mean()})
    }
}

/// A distribution of durations in ns, log-linear: exact below 64 ns, then 64 buckets per power
/// of two.
#[derive(Debug, Clone)]
pub struct NsHistogram {
    counts: Vec<u64>,
    n: u64,
    max: u64,
    sum: u64,
}

const NS_BUCKETS: usize = 64 * 59;

impl Default for NsHistogram {
    fn default() -> Self {
        NsHistogram { counts: vec![0; NS_BUCKETS], n: 0, max: 0, sum: 0 }
    }
}

fn ns_bucket(ns: u64) -> usize {
    if ns < 64 {
        return ns as usize;
    }
    let e = 63 - ns.leading_zeros() as usize; // 6..=63
    let sub = ((ns >> (e - 6)) & 63) as usize;
    ((e - 5) * 64 + sub).min(NS_BUCKETS - 1)
}

/// The smallest duration of bucket `b`.
fn ns_value(b: usize) -> u64 {
    if b < 64 {
        return b as u64;
    }
    let (e, sub) = (b / 64 + 5, (b % 64) as u128);
    ((64 + sub) << (e - 6)).min(u128::from(u64::MAX)) as u64
}

impl NsHistogram {
    pub fn add(&mut self, ns: u64) {
        if let Some(c) = self.counts.get_mut(ns_bucket(ns)) {
            *c += 1;
        }
        self.n += 1;
        self.max = self.max.max(ns);
        self.sum = self.sum.saturating_add(ns);
    }
    pub fn count(&self) -> u64 {
        self.n
    }
    pub fn max(&self) -> u64 {
        self.max
    }
    pub fn mean(&self) -> u64 {
        self.sum.checked_div(self.n).unwrap_or(0)
    }
    /// The smallest value with at least `q` (0..=1) of the samples at or below it, to the
    /// resolution of its bucket (the bucket's middle, never above the maximum).
    pub fn quantile(&self, q: f64) -> u64 {
        if self.n == 0 {
            return 0;
        }
        let want = ((q * self.n as f64).ceil() as u64).clamp(1, self.n);
        let mut seen = 0u64;
        for (b, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen >= want {
                let (lo, hi) = (ns_value(b), ns_value(b + 1));
                return (lo + (hi - lo) / 2).min(self.max);
            }
        }
        self.max
    }
    /// `{"p50":…,"p99":…,"max":…,"mean":…}` in ns.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({"p50": self.quantile(0.5), "p99": self.quantile(0.99), "max": self.max, "mean": self.mean()})
    }
}

/// What a run measured.
#[derive(Debug, Clone, Default)]
pub struct ScanStats {
    /// Scans run.
    pub scans: u64,
    /// Lateness of each scan's start against its deadline on the period grid, µs.
    pub jitter: Histogram,
    /// Time each scan took (inputs, chart, outputs, monitor state), µs.
    pub duration: Histogram,
    /// The same in ns, for scans shorter than a microsecond.
    pub duration_ns: NsHistogram,
    /// Scans that ended after the next deadline.
    pub overruns: u64,
    /// Grid periods skipped because of overruns (virtual time skipped them too).
    pub skipped: u64,
}

impl ScanStats {
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "scans": self.scans,
            "jitterUs": self.jitter.to_json(),
            "scanUs": self.duration.to_json(),
            "scanNs": self.duration_ns.to_json(),
            "overruns": self.overruns,
            "skipped": self.skipped,
        })
    }
    /// One line for a terminal: `scans 1000, jitter p50 12 µs p99 80 µs max 300 µs, …` (scan
    /// times to 0.1 µs).
    pub fn summary(&self) -> String {
        let us = |ns: u64| format!("{:.1}", ns as f64 / 1000.0);
        format!(
            "{} scans; start jitter p50 {} µs, p99 {} µs, max {} µs; scan time p50 {} µs, p99 {} µs, max {} µs; {} overruns, {} periods skipped",
            self.scans,
            self.jitter.quantile(0.5),
            self.jitter.quantile(0.99),
            self.jitter.max(),
            us(self.duration_ns.quantile(0.5)),
            us(self.duration_ns.quantile(0.99)),
            us(self.duration_ns.max()),
            self.overruns,
            self.skipped
        )
    }

    /// What [`ScanStats::to_json`] shows, without the histograms (cheap to copy and publish).
    pub fn digest(&self) -> StatsDigest {
        StatsDigest {
            scans: self.scans,
            jitter: [self.jitter.quantile(0.5), self.jitter.quantile(0.99), self.jitter.max(), self.jitter.mean()],
            duration: [
                self.duration.quantile(0.5),
                self.duration.quantile(0.99),
                self.duration.max(),
                self.duration.mean(),
            ],
            duration_ns: [
                self.duration_ns.quantile(0.5),
                self.duration_ns.quantile(0.99),
                self.duration_ns.max(),
                self.duration_ns.mean(),
            ],
            overruns: self.overruns,
            skipped: self.skipped,
        }
    }
}

/// The figures of [`ScanStats`]: p50, p99, max and mean of each distribution.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StatsDigest {
    pub scans: u64,
    pub jitter: [u64; 4],
    pub duration: [u64; 4],
    pub duration_ns: [u64; 4],
    pub overruns: u64,
    pub skipped: u64,
}

impl StatsDigest {
    /// The line [`ScanStats::summary`] prints, from the figures.
    pub fn summary(&self) -> String {
        let us = |ns: u64| format!("{:.1}", ns as f64 / 1000.0);
        format!(
            "{} scans; start jitter p50 {} µs, p99 {} µs, max {} µs; scan time p50 {} µs, p99 {} µs, max {} µs; {} overruns, {} periods skipped",
            self.scans,
            self.jitter[0],
            self.jitter[1],
            self.jitter[2],
            us(self.duration_ns[0]),
            us(self.duration_ns[1]),
            us(self.duration_ns[2]),
            self.overruns,
            self.skipped
        )
    }

    /// The same JSON as [`ScanStats::to_json`].
    pub fn to_json(&self) -> serde_json::Value {
        let q = |v: &[u64; 4]| serde_json::json!({"p50": v[0], "p99": v[1], "max": v[2], "mean": v[3]});
        serde_json::json!({
            "scans": self.scans,
            "jitterUs": q(&self.jitter),
            "scanUs": q(&self.duration),
            "scanNs": q(&self.duration_ns),
            "overruns": self.overruns,
            "skipped": self.skipped,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_of_a_known_distribution() {
        let mut h = Histogram::default();
        for us in 1..=100 {
            h.add(us);
        }
        h.add(250_000);
        assert_eq!(h.quantile(0.5), 51);
        assert_eq!(h.quantile(0.99), 100);
        assert_eq!(h.quantile(1.0), 250_000);
        assert_eq!(h.max(), 250_000);
        assert_eq!(Histogram::default().quantile(0.5), 0);
    }

    #[test]
    fn nanosecond_quantiles_within_two_percent() {
        let mut h = NsHistogram::default();
        for ns in [40, 90, 95, 1_000, 42_000, 10_000_000] {
            h.add(ns);
        }
        assert_eq!(h.quantile(0.1), 40);
        let p50 = h.quantile(0.5) as f64;
        assert!((p50 - 95.0).abs() <= 2.0, "{p50}");
        assert_eq!(h.quantile(1.0), 10_000_000);
        for ns in [64u64, 65, 127, 128, 1_000_003, u64::MAX / 3] {
            let b = ns_bucket(ns);
            assert!(ns_value(b) <= ns && ns < ns_value(b + 1), "{ns} in bucket {b}");
        }
    }
}
