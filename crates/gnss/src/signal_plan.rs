//! Which systems and signals a solution uses, and the per-satellite observation it
//! takes from an epoch of every signal ([`SatSignals`]): the code, the carrier phase
//! and Doppler of the same signal, its frequency, and optionally the dual-frequency
//! ionosphere-free code. See docs/GNSS.md "Signal selection".

use crate::obs::SatSignals;
use crate::signal::{attribute_priority, carrier_frequency_hz, iono_free_code, ObsCode};
use navfuse_core::sat::{SatId, System};

/// The band a single-frequency user of each system tracks first: L1/E1 (GPS,
/// QZSS, Galileo, GLONASS G1), B1I (BeiDou band 2), L5 (NavIC); SBAS is not used for
/// ranging here.
pub fn default_band(system: System) -> Option<u8> {
    match system {
        System::Gps | System::Qzss | System::Galileo | System::Glonass => Some(1),
        System::BeiDou => Some(2),
        System::Navic => Some(5),
        System::Sbas => None,
    }
}

/// Systems and signals to use.
#[derive(Clone, Debug, PartialEq)]
pub struct SignalPlan {
    /// Systems used (others are ignored).
    pub systems: Vec<System>,
    /// Per system, the codes to use in order of preference (e.g. `C1P`, `C1C` for
    /// GLONASS); a system not listed uses its [`default_band`] with the documented
    /// attribute priority ([`attribute_priority`]).
    pub codes: Vec<(System, Vec<ObsCode>)>,
    /// Use the ionosphere-free combination of two codes where a satellite has both
    /// (`signal::iono_free_bands`); the others keep their single code.
    pub dual_frequency: bool,
}

impl Default for SignalPlan {
    /// GPS only, L1 C/A first.
    fn default() -> Self {
        SignalPlan::systems(vec![System::Gps])
    }
}

/// One satellite's chosen observations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChosenSignal {
    pub sat: SatId,
    /// The code used (the first of the pair when `iono_free`).
    pub code: ObsCode,
    /// Pseudorange \[m\] (ionosphere-free when `iono_free_with`).
    pub pseudorange_m: f64,
    /// The second band of the ionosphere-free combination.
    pub iono_free_with: Option<u8>,
    /// Carrier frequency of `code` \[Hz\].
    pub frequency_hz: f64,
    /// Carrier phase of the same signal \[cycles\].
    pub carrier_cycles: Option<f64>,
    /// Its loss-of-lock indicator (0 when blank).
    pub lli: u8,
    /// Doppler of the same signal (else of the band) \[Hz\].
    pub doppler_hz: Option<f64>,
    /// Signal strength of the same signal [dB-Hz].
    pub cn0_dbhz: Option<f64>,
}

impl SignalPlan {
    /// These systems with their default signals, single frequency.
    pub fn systems(systems: Vec<System>) -> Self {
        SignalPlan {
            systems,
            codes: Vec::new(),
            dual_frequency: false,
        }
    }

    pub fn uses(&self, system: System) -> bool {
        self.systems.contains(&system)
    }

    /// The code of `sat` to use: the first configured code present, else the
    /// default band's by priority; None when the satellite's system is not used or
    /// it has no such code with a value.
    fn code(&self, sat: &SatSignals) -> Option<(ObsCode, f64)> {
        let sys = sat.sat.system;
        let has = |c: ObsCode| sat.get(c).and_then(|v| v.value).map(|v| (c, v));
        if let Some((_, list)) = self.codes.iter().find(|(s, _)| *s == sys) {
            return list.iter().find_map(|&c| has(c));
        }
        let band = default_band(sys)?;
        attribute_priority(sys, band)?
            .iter()
            .find_map(|&a| has(ObsCode([b'C', b'0' + band, a])))
    }

    /// The observations of one satellite (`glonass_channel`: its FDMA channel, from
    /// the observation header or the navigation record).
    pub fn choose(&self, sat: &SatSignals, glonass_channel: Option<i8>) -> Option<ChosenSignal> {
        let sys = sat.sat.system;
        if !self.uses(sys) {
            return None;
        }
        let (code, pr) = self.code(sat)?;
        let frequency_hz = carrier_frequency_hz(sys, code.band(), glonass_channel)?;
        let same = |kind: u8| ObsCode([kind, code.0[1], code.0[2]]);
        let value = |c: ObsCode| sat.get(c).and_then(|v| v.value);
        let carrier = sat.get(same(b'L')).filter(|v| v.value.is_some());
        // Doppler of the same signal, else any Doppler on the band (the same carrier).
        let doppler_hz = value(same(b'D')).or_else(|| {
            sat.signals
                .iter()
                .find(|(c, v)| c.kind() == b'D' && c.band() == code.band() && v.value.is_some())
                .and_then(|(_, v)| v.value)
        });
        let iono_free = if self.dual_frequency {
            iono_free_code(sat, glonass_channel).filter(|f| f.first == code)
        } else {
            None
        };
        Some(ChosenSignal {
            sat: sat.sat,
            code,
            pseudorange_m: iono_free.map_or(pr, |f| f.pseudorange_m),
            iono_free_with: iono_free.map(|f| f.second.band()),
            frequency_hz,
            carrier_cycles: carrier.and_then(|v| v.value),
            lli: carrier.and_then(|v| v.lli).unwrap_or(0),
            doppler_hz,
            cn0_dbhz: value(same(b'S')),
        })
    }
}

/// Parse a system list such as `G,E,C`, `GREC`, `g,e` or `GPS,Galileo` (letters in
/// either case, or system names, separated by commas or spaces).
pub fn parse_systems(s: &str) -> Result<Vec<System>, String> {
    let mut out = Vec::new();
    let mut add = |sys: System| -> Result<(), String> {
        if sys == System::Sbas {
            return Err("S (SBAS) is not used for ranging".into());
        }
        if !out.contains(&sys) {
            out.push(sys);
        }
        Ok(())
    };
    for token in s.split([',', ' ']).filter(|t| !t.is_empty()) {
        if let Some(sys) = System::ALL
            .iter()
            .find(|x| x.name().eq_ignore_ascii_case(token))
        {
            add(*sys)?;
            continue;
        }
        for c in token.chars() {
            let sys = System::from_letter(c.to_ascii_uppercase())
                .ok_or_else(|| format!("'{c}' in '{token}' is not a system letter (G R E C J I) or name (GPS, Galileo, ...)"))?;
            add(sys)?;
        }
    }
    if out.is_empty() {
        return Err("no system given (expected letters such as G,R,E,C,J)".into());
    }
    Ok(out)
}

/// Parse code preferences such as `R:C1P+C1C,E:C1X` (system letter, colon, codes
/// in order joined by `+`).
pub fn parse_codes(s: &str) -> Result<Vec<(System, Vec<ObsCode>)>, String> {
    let mut out: Vec<(System, Vec<ObsCode>)> = Vec::new();
    for item in s.split(',').map(str::trim).filter(|x| !x.is_empty()) {
        let (sys, codes) = item
            .split_once(':')
            .ok_or_else(|| format!("'{item}': expected SYSTEM:CODE[+CODE...], e.g. R:C1P"))?;
        let mut letters = sys.trim().chars();
        let sys = match (letters.next(), letters.next()) {
            (Some(c), None) => System::from_letter(c).filter(|_| c != ' '),
            _ => None,
        }
        .ok_or_else(|| format!("'{item}': '{sys}' is not a system letter (G R E C J I)"))?;
        let list = codes
            .split('+')
            .map(|c| {
                let c = c.trim();
                ObsCode::parse(c)
                    .filter(|k| k.kind() == b'C')
                    .ok_or_else(|| format!("'{item}': '{c}' is not a RINEX 3 code observation (C1C, C2I, C1P, ...)"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        out.retain(|(s, _)| *s != sys);
        out.push((sys, list));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::obs::ObsValue;

    fn sat(system: System, obs: &[(&str, f64)]) -> SatSignals {
        SatSignals {
            sat: SatId::new(system, 3),
            signals: obs
                .iter()
                .map(|&(c, v)| (ObsCode::parse(c).unwrap(), ObsValue::new(v)))
                .collect(),
        }
    }

    #[test]
    fn default_and_configured_signals() {
        let r = sat(
            System::Glonass,
            &[
                ("C1C", 1.0),
                ("C1P", 2.0),
                ("L1C", 10.0),
                ("L1P", 20.0),
                ("D1C", 5.0),
            ],
        );
        let mut plan = SignalPlan::systems(vec![System::Glonass, System::BeiDou]);
        let c = plan.choose(&r, Some(1)).unwrap();
        assert_eq!((c.code.to_string(), c.pseudorange_m), ("C1C".into(), 1.0));
        assert_eq!(c.carrier_cycles, Some(10.0));
        assert!((c.frequency_hz - 1602.5625e6).abs() < 1.0);
        // GLONASS without a channel: no frequency, not used.
        assert!(plan.choose(&r, None).is_none());
        plan.codes = parse_codes("R:C1P+C1C").unwrap();
        let c = plan.choose(&r, Some(1)).unwrap();
        assert_eq!(
            (c.code.to_string(), c.carrier_cycles),
            ("C1P".into(), Some(20.0))
        );
        // Doppler of the band when the signal has none.
        assert_eq!(c.doppler_hz, Some(5.0));
        let b = sat(System::BeiDou, &[("C2I", 7.0), ("C6I", 8.0)]);
        let c = plan.choose(&b, None).unwrap();
        assert_eq!(c.code.to_string(), "C2I");
        assert!((c.frequency_hz - 1561.098e6).abs() < 1.0);
        // A system not in the plan.
        assert!(plan
            .choose(&sat(System::Gps, &[("C1C", 1.0)]), None)
            .is_none());
    }

    #[test]
    fn parsing() {
        assert_eq!(
            parse_systems("G,R, E C").unwrap(),
            vec![
                System::Gps,
                System::Glonass,
                System::Galileo,
                System::BeiDou
            ]
        );
        assert!(parse_systems("G,X").unwrap_err().contains("'X'"));
        assert_eq!(
            parse_systems("gps, Galileo,c").unwrap(),
            vec![System::Gps, System::Galileo, System::BeiDou]
        );
        assert!(parse_systems("gpx").unwrap_err().contains("'p' in 'gpx'"));
        assert!(parse_systems("").is_err());
        assert!(parse_systems("S").is_err());
        assert!(parse_codes("R=C1P").unwrap_err().contains("SYSTEM:CODE"));
        assert!(parse_codes("R:L1P")
            .unwrap_err()
            .contains("code observation"));
        let c = parse_codes("R:C1P+C1C, E:C1X").unwrap();
        assert_eq!(c.len(), 2);
        assert_eq!(c[0].1[1].to_string(), "C1C");
    }
}
