//! The Allan deviation plots of `navfuse allan --svg DIR`: one log-log chart per
//! sensor, each axis with its error bars as a band (adev (1 +- rel_error)), the
//! fitted random-walk line and the bias-instability point.

use crate::chart::{palette, Band, Chart, Series, Style};
use crate::{Error, Figure};
use navfuse_core::allan::imu::{ImuAllan, Sensor};

/// The gyro and the accelerometer charts.
pub fn allan_figures(al: &ImuAllan) -> Result<Vec<Figure>, Error> {
    let mut out = Vec::new();
    for sensor in [Sensor::Gyro, Sensor::Accel] {
        let u = sensor.units();
        let mut chart = Chart::new(
            format!("Allan deviation, {}", sensor.name()),
            "averaging time tau [s]",
            u.adev,
        );
        chart.log_x = true;
        chart.log_y = true;
        chart.size = (900, 520);
        for (k, ax) in al.axes.iter().filter(|a| a.sensor == sensor).enumerate() {
            let f = u.adev_factor;
            let colour = palette(k);
            chart.series.push(Series::line(
                ax.name(),
                colour,
                ax.curve.iter().map(|p| (p.tau_s, p.adev * f)).collect(),
            ));
            chart.bands.push(Band {
                name: String::new(),
                colour,
                points: ax
                    .curve
                    .iter()
                    .filter(|p| p.rel_error.is_finite() && p.rel_error < 1.0)
                    .map(|p| {
                        (
                            p.tau_s,
                            p.adev * f * (1.0 - p.rel_error),
                            p.adev * f * (1.0 + p.rel_error),
                        )
                    })
                    .collect(),
            });
            if let Some(rw) = ax.random_walk {
                // sigma = N / sqrt(tau) over the fitted range, extended to tau = 1 s.
                let (lo, hi) = (rw.tau_lo_s.min(1.0), rw.tau_hi_s.max(1.0));
                let n = rw.coefficient * f;
                chart.series.push(Series::line(
                    format!(
                        "{} {} = {:.4} {}",
                        ax.name(),
                        sensor.random_walk_name(),
                        rw.coefficient * u.random_walk_factor,
                        u.random_walk
                    ),
                    colour,
                    vec![(lo, n / lo.sqrt()), (hi, n / hi.sqrt())],
                ));
            }
            if let Some(bi) = ax.bias_instability {
                chart.series.push(Series {
                    name: format!(
                        "{} bias instability {}{:.3} {}",
                        ax.name(),
                        if bi.still_falling { "<= " } else { "" },
                        bi.value * f,
                        u.adev
                    ),
                    colour,
                    style: Style::Points(4),
                    pieces: vec![vec![(bi.tau_s, bi.value * f * 0.664)]],
                });
            }
        }
        out.push(Figure {
            name: format!("allan_{}", sensor.name()),
            section: "Allan deviation",
            caption: format!(
                "Overlapping Allan deviation of the {} axes [{}] with 1-sigma error bands, the fitted random-walk line (-1/2 slope) and the minimum (bias instability = minimum / 0.664)",
                sensor.name(),
                u.adev
            ),
            svg: chart.svg().map_err(Error::new)?,
        });
    }
    Ok(out)
}
