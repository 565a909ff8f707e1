//! A target profile the designer writes: points in the config or a two-column CSV file, joined by
//! straight lines or by a monotone cubic (PCHIP, Fritsch–Carlson), so a monotone profile never
//! overshoots between its points.
//!
//! Positions run from the clamp (0) to the tip (1) and must cover both ends. Deflections are
//! normalized on loading to 0 at the clamp and 1 at the tip, so a profile may be written in any
//! unit (mm measured off a drawing, say); only its shape matters to the fitness.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::task::SceneError;

/// The most points a custom profile may have (a CSV from a scanner is thinned first).
pub const MAX_PROFILE_POINTS: usize = 10_000;

/// How a custom profile is read between its points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Interpolation {
    /// Straight lines between points.
    Linear,
    /// A piecewise cubic with Fritsch–Carlson slopes: C¹, exact at the points, and monotone
    /// wherever the points are (the default).
    #[default]
    Pchip,
}

/// What is wrong with a custom profile, naming the file and line or the point.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TargetError {
    #[error("cannot read {file}: {message}")]
    Read { file: String, message: String },
    #[error("{file} line {line}: {message}")]
    Csv {
        file: String,
        line: usize,
        message: String,
    },
    #[error("points[{index}]: {message}")]
    Point { index: usize, message: String },
    #[error("{0}")]
    Profile(String),
}

/// A designer's profile as written (points, or the CSV file they came from) and the normalized
/// curve the fitness reads.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "WrittenProfile", into = "WrittenProfile")]
pub struct CustomProfile {
    written: WrittenProfile,
    curve: Curve,
}

/// The profile as a config writes it. Once a CSV is loaded its points are kept beside the file
/// name, so workers and a resumed run use the points the run started with, never a file edited
/// since.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WrittenProfile {
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    points: Vec<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    csv: Option<String>,
    #[serde(default)]
    interpolation: Interpolation,
}

/// Normalized positions and deflections with the slope at each point.
#[derive(Clone, Debug, Default, PartialEq)]
struct Curve {
    t: Vec<f64>,
    f: Vec<f64>,
    slope: Vec<f64>,
}

impl TryFrom<WrittenProfile> for CustomProfile {
    type Error = TargetError;

    fn try_from(written: WrittenProfile) -> Result<Self, TargetError> {
        if written.points.is_empty() && written.csv.is_none() {
            return Err(TargetError::Profile(
                "a custom target needs `points` or `csv`".into(),
            ));
        }
        // A CSV not yet loaded has no curve; `load_csv` builds it (a config does on loading).
        let curve = if written.points.is_empty() {
            Curve::default()
        } else {
            Curve::new(&written.points, written.interpolation)?
        };
        Ok(Self { written, curve })
    }
}

impl From<CustomProfile> for WrittenProfile {
    fn from(p: CustomProfile) -> Self {
        p.written
    }
}

impl CustomProfile {
    /// A profile through `points` (position, deflection).
    pub fn from_points(
        points: Vec<[f64; 2]>,
        interpolation: Interpolation,
    ) -> Result<Self, TargetError> {
        Self::try_from(WrittenProfile {
            points,
            csv: None,
            interpolation,
        })
    }

    /// Reads the CSV file the profile names, relative to `base_dir` (the config's folder), unless
    /// its points are already there.
    pub fn load_csv(&mut self, base_dir: &Path) -> Result<(), TargetError> {
        let Some(file) = &self.written.csv else {
            return Ok(());
        };
        if !self.written.points.is_empty() {
            return Ok(());
        }
        let path = base_dir.join(file);
        let text = std::fs::read_to_string(&path).map_err(|e| TargetError::Read {
            file: path.display().to_string(),
            message: e.to_string(),
        })?;
        let points = parse_csv(&text, &path.display().to_string())?;
        self.curve = Curve::new(&points, self.written.interpolation)?;
        self.written.points = points;
        Ok(())
    }

    pub fn validate(&self) -> Result<(), SceneError> {
        if self.curve.t.is_empty() {
            return Err(SceneError::new(
                "target.csv",
                format!(
                    "{} has not been loaded (a config loads it relative to its own folder)",
                    self.written.csv.as_deref().unwrap_or("-")
                ),
            ));
        }
        Ok(())
    }

    /// "my_profile.csv" or "custom (N points)".
    pub fn label(&self) -> String {
        match &self.written.csv {
            Some(file) => file.clone(),
            None => format!("custom ({} points)", self.written.points.len()),
        }
    }

    /// Normalized deflection at `t` ∈ [0, 1].
    pub fn deflection(&self, t: f64) -> f64 {
        self.curve.at(t)
    }
}

/// Two columns per line: position, deflection. A first line that is not two numbers is a header;
/// blank lines and lines starting with `#` are skipped; a comma, semicolon, tab or spaces
/// separate the columns.
fn parse_csv(text: &str, file: &str) -> Result<Vec<[f64; 2]>, TargetError> {
    let mut points = Vec::new();
    let mut seen_data = false;
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line
            .split([',', ';', '\t', ' '])
            .filter(|f| !f.is_empty())
            .collect();
        let numbers: Option<Vec<f64>> = fields.iter().map(|f| f.parse().ok()).collect();
        match (numbers, fields.len()) {
            (Some(n), 2) => {
                points.push([n[0], n[1]]);
                seen_data = true;
            }
            (None, _) if !seen_data && points.is_empty() => {} // the header
            _ => {
                return Err(TargetError::Csv {
                    file: file.into(),
                    line: line_no,
                    message: format!("expected two numbers (position, deflection), got '{line}'"),
                });
            }
        }
        if points.len() > MAX_PROFILE_POINTS {
            return Err(TargetError::Csv {
                file: file.into(),
                line: line_no,
                message: format!("more than {MAX_PROFILE_POINTS} points"),
            });
        }
    }
    Curve::check(&points).map_err(|e| match e {
        TargetError::Point { index, message } => TargetError::Csv {
            file: file.into(),
            line: line_of_point(text, index),
            message,
        },
        other => other,
    })?;
    Ok(points)
}

/// The 1-based line of the `index`-th data row, for error messages.
fn line_of_point(text: &str, index: usize) -> usize {
    let mut seen = 0;
    for (i, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line
            .trim()
            .split([',', ';', '\t', ' '])
            .filter(|f| !f.is_empty())
            .collect();
        if fields.len() == 2 && fields.iter().all(|f| f.parse::<f64>().is_ok()) {
            if seen == index {
                return i + 1;
            }
            seen += 1;
        }
    }
    0
}

impl Curve {
    /// Positions finite, strictly increasing, from exactly 0 to exactly 1; deflections finite
    /// with the tip's different from the clamp's; 2 to [`MAX_PROFILE_POINTS`] points.
    fn check(points: &[[f64; 2]]) -> Result<(), TargetError> {
        if points.len() < 2 || points.len() > MAX_PROFILE_POINTS {
            return Err(TargetError::Profile(format!(
                "a profile needs 2 to {MAX_PROFILE_POINTS} points, got {}",
                points.len()
            )));
        }
        for (index, &[t, f]) in points.iter().enumerate() {
            let bad = |message: String| Err(TargetError::Point { index, message });
            if !(t.is_finite() && f.is_finite()) {
                return bad(format!("[{t}, {f}] is not finite"));
            }
            if !(0.0..=1.0).contains(&t) {
                return bad(format!("position {t} is outside [0, 1] (clamp 0, tip 1)"));
            }
            if index > 0 && t <= points[index - 1][0] {
                return bad(format!(
                    "position {t} does not increase (the point before is at {})",
                    points[index - 1][0]
                ));
            }
        }
        let (first, last) = (points[0], points[points.len() - 1]);
        if first[0] != 0.0 || last[0] != 1.0 {
            return Err(TargetError::Profile(format!(
                "positions must cover the beam from 0 (clamp) to 1 (tip); they run from {} to {}",
                first[0], last[0]
            )));
        }
        if first[1] == last[1] {
            return Err(TargetError::Profile(
                "the tip's deflection equals the clamp's, so the profile cannot be normalized"
                    .into(),
            ));
        }
        Ok(())
    }

    fn new(points: &[[f64; 2]], interpolation: Interpolation) -> Result<Self, TargetError> {
        Self::check(points)?;
        let (f0, f1) = (points[0][1], points[points.len() - 1][1]);
        let t: Vec<f64> = points.iter().map(|p| p[0]).collect();
        let f: Vec<f64> = points.iter().map(|p| (p[1] - f0) / (f1 - f0)).collect();
        let slope = match interpolation {
            Interpolation::Linear => Vec::new(),
            Interpolation::Pchip => pchip_slopes(&t, &f),
        };
        Ok(Self { t, f, slope })
    }

    fn at(&self, x: f64) -> f64 {
        let n = self.t.len();
        if n == 0 {
            return f64::NAN;
        }
        let x = x.clamp(0.0, 1.0);
        // The interval [t_i, t_{i+1}] holding x.
        let i = self.t.partition_point(|&t| t <= x).clamp(1, n - 1) - 1;
        let (x0, x1, y0, y1) = (self.t[i], self.t[i + 1], self.f[i], self.f[i + 1]);
        let h = x1 - x0;
        let s = (x - x0) / h;
        if self.slope.is_empty() {
            return y0 + s * (y1 - y0);
        }
        // Cubic Hermite basis on [0, 1].
        let (s2, s3) = (s * s, s * s * s);
        let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
        let h10 = s3 - 2.0 * s2 + s;
        let h01 = -2.0 * s3 + 3.0 * s2;
        let h11 = s3 - s2;
        h00 * y0 + h10 * h * self.slope[i] + h01 * y1 + h11 * h * self.slope[i + 1]
    }
}

/// Fritsch–Carlson slopes: zero at a local extremum of the data, elsewhere the weighted harmonic
/// mean of the neighbouring secants; at the ends a one-sided three-point estimate limited so the
/// end interval stays monotone.
fn pchip_slopes(t: &[f64], f: &[f64]) -> Vec<f64> {
    let n = t.len();
    let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let delta: Vec<f64> = (0..n - 1).map(|i| (f[i + 1] - f[i]) / h[i]).collect();
    if n == 2 {
        return vec![delta[0]; 2];
    }
    let mut d = vec![0.0; n];
    for i in 1..n - 1 {
        if delta[i - 1] * delta[i] > 0.0 {
            let w1 = 2.0 * h[i] + h[i - 1];
            let w2 = h[i] + 2.0 * h[i - 1];
            d[i] = (w1 + w2) / (w1 / delta[i - 1] + w2 / delta[i]);
        }
    }
    let end = |h0: f64, h1: f64, d0: f64, d1: f64| {
        let d = ((2.0 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
        if d.signum() != d0.signum() || d0 == 0.0 {
            0.0
        } else if d0.signum() != d1.signum() && d.abs() > 3.0 * d0.abs() {
            3.0 * d0
        } else {
            d
        }
    };
    d[0] = end(h[0], h[1], delta[0], delta[1]);
    d[n - 1] = end(h[n - 2], h[n - 3], delta[n - 2], delta[n - 3]);
    d
}
