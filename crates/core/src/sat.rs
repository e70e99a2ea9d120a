//! Satellite identity across constellations: the system (RINEX 3/4 letters, RINEX
//! 3.05 §3.5 / 4.00 §4.1) and the number within it, written `G05`, `E11`, `C35`.
//! Here in the core because the filter's measurements and inter-system bias states
//! name them; the GNSS layer re-exports them.

/// A satellite navigation system, by its RINEX letter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum System {
    /// GPS (G).
    Gps,
    /// GLONASS (R).
    Glonass,
    /// Galileo (E).
    Galileo,
    /// BeiDou (C).
    BeiDou,
    /// QZSS (J).
    Qzss,
    /// SBAS payloads (S).
    Sbas,
    /// NavIC / IRNSS (I).
    Navic,
}

impl System {
    pub const ALL: [System; 7] = [
        System::Gps,
        System::Glonass,
        System::Galileo,
        System::BeiDou,
        System::Qzss,
        System::Sbas,
        System::Navic,
    ];

    /// Position in [`System::ALL`] (for per-system arrays).
    pub fn index(self) -> usize {
        self as usize
    }

    /// The RINEX letter.
    pub fn letter(self) -> char {
        match self {
            System::Gps => 'G',
            System::Glonass => 'R',
            System::Galileo => 'E',
            System::BeiDou => 'C',
            System::Qzss => 'J',
            System::Sbas => 'S',
            System::Navic => 'I',
        }
    }

    /// From a RINEX letter (a blank is GPS, as RINEX 2 allows).
    pub fn from_letter(c: char) -> Option<System> {
        match c {
            'G' | ' ' => Some(System::Gps),
            'R' => Some(System::Glonass),
            'E' => Some(System::Galileo),
            'C' => Some(System::BeiDou),
            'J' => Some(System::Qzss),
            'S' => Some(System::Sbas),
            'I' => Some(System::Navic),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            System::Gps => "GPS",
            System::Glonass => "GLONASS",
            System::Galileo => "Galileo",
            System::BeiDou => "BeiDou",
            System::Qzss => "QZSS",
            System::Sbas => "SBAS",
            System::Navic => "NavIC",
        }
    }
}

/// One satellite: its system and its number in it (PRN; GLONASS slot; SBAS PRN - 100
/// as RINEX writes it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SatId {
    pub system: System,
    pub prn: u8,
}

impl SatId {
    pub const fn new(system: System, prn: u8) -> Self {
        SatId { system, prn }
    }

    pub const fn gps(prn: u8) -> Self {
        SatId {
            system: System::Gps,
            prn,
        }
    }

    /// Parse `G05`, `E11`, `R 3`, ` 7` (RINEX 2: blank = GPS); None otherwise.
    pub fn parse(s: &str) -> Option<SatId> {
        let mut chars = s.chars();
        let system = System::from_letter(chars.next()?)?;
        let prn: u8 = chars.as_str().trim().parse().ok()?;
        (prn > 0).then_some(SatId { system, prn })
    }
}

impl std::fmt::Display for SatId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}{:02}", self.system.letter(), self.prn)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_and_display() {
        assert_eq!(SatId::parse("G05"), Some(SatId::gps(5)));
        assert_eq!(SatId::parse("E11").unwrap().to_string(), "E11");
        assert_eq!(SatId::parse("R 3"), Some(SatId::new(System::Glonass, 3)));
        assert_eq!(SatId::parse(" 7"), Some(SatId::gps(7)));
        assert_eq!(SatId::parse("X01"), None);
        assert_eq!(SatId::parse("G00"), None);
        assert_eq!(SatId::parse("Gxx"), None);
        for (i, s) in System::ALL.into_iter().enumerate() {
            assert_eq!(System::from_letter(s.letter()), Some(s));
            assert_eq!(s.index(), i);
        }
        assert!(SatId::parse("G02") < SatId::parse("R01"));
    }
}
