//! Error-state layout. The 21 INS states come first in a fixed order; the INS-level
//! extra blocks (time offset, odometer scale, mounting) and the aiding sources' own
//! blocks (receiver clock, fix error, `Block::Source`) follow, without changing the
//! filter.
//!
//! Error conventions: position, velocity, attitude, time offset, receiver clock and
//! vehicle states are x_est - x_true (position in NED metres, velocity NED \[m/s\],
//! attitude phi with
//! C_b^n,est = (I - phi x) C_b^n,true, mounting dalpha with C_b^m,est =
//! (I - dalpha x) C_b^m,true, odometer scale dk); the twelve IMU error states are
//! x_true - x_est (KF-GINS), added to the estimates at feedback, in SI units (rad/s,
//! m/s², unitless scale).

/// A named block of error states.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Block {
    Position,
    Velocity,
    Attitude,
    GyroBias,
    AccelBias,
    GyroScale,
    AccelScale,
    /// GNSS-to-IMU time offset \[s\].
    TimeOffset,
    /// Rate of the GNSS-to-IMU time offset \[s/s\].
    TimeOffsetRate,
    /// Odometer scale-factor error dk \[-\] (SYSTEM.md §4b; seed 004 eq. 3).
    OdometerScale,
    /// IMU-to-vehicle mounting angle errors: pitch, yaw \[rad\] (seed 004 dalpha_p,
    /// dalpha_y; roll about the forward axis is not observable from the vehicle
    /// velocity and is not estimated).
    Mounting,
    /// Receiver clock bias c dt_r \[m\] (tight coupling; seed 000 eq. 19-22).
    ClockBias,
    /// Receiver clock drift c dt_r' \[m/s\] (seed 000 eq. 23-28).
    ClockDrift,
    /// Time-correlated error of the loosely coupled GNSS fixes, NED \[m\]
    /// (fix_error.rs), b_est - b_true.
    GnssBias,
    /// A block an aiding source defines in its own file (aiding/source.rs): its
    /// name and number of states. A new source adds its states without touching
    /// this list.
    Source {
        name: &'static str,
        len: usize,
    },
}

impl Block {
    /// Whether the block has no states (none has).
    pub fn is_empty(self) -> bool {
        self.len() == 0
    }

    pub fn len(self) -> usize {
        match self {
            Block::TimeOffset
            | Block::TimeOffsetRate
            | Block::OdometerScale
            | Block::ClockBias
            | Block::ClockDrift => 1,
            Block::Mounting => 2,
            Block::Source { len, .. } => len,
            _ => 3,
        }
    }
}

/// The filter's state vector: an ordered list of blocks.
#[derive(Clone, Debug, PartialEq)]
pub struct StateLayout {
    blocks: Vec<(Block, usize)>,
    n: usize,
}

/// Indices of the 21 INS states (the layout always starts with them).
pub const POS: usize = 0;
pub const VEL: usize = 3;
pub const ATT: usize = 6;
pub const BG: usize = 9;
pub const BA: usize = 12;
pub const SG: usize = 15;
pub const SA: usize = 18;
pub const N_INS: usize = 21;

impl StateLayout {
    /// Position, velocity, attitude, gyro/accel bias, gyro/accel scale (21 states).
    pub fn ins21() -> Self {
        let mut l = StateLayout {
            blocks: Vec::new(),
            n: 0,
        };
        for b in [
            Block::Position,
            Block::Velocity,
            Block::Attitude,
            Block::GyroBias,
            Block::AccelBias,
            Block::GyroScale,
            Block::AccelScale,
        ] {
            l.push(b);
        }
        l
    }

    /// Append a block (no-op if present). Returns its first index.
    pub fn push(&mut self, b: Block) -> usize {
        if let Some(i) = self.index(b) {
            return i;
        }
        let i = self.n;
        self.blocks.push((b, i));
        self.n += b.len();
        i
    }

    /// First index of a block, if the layout has it.
    pub fn index(&self, b: Block) -> Option<usize> {
        self.blocks.iter().find(|(k, _)| *k == b).map(|(_, i)| *i)
    }

    /// Total number of states.
    pub fn len(&self) -> usize {
        self.n
    }

    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    pub fn blocks(&self) -> impl Iterator<Item = (Block, usize)> + '_ {
        self.blocks.iter().copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_extends() {
        let mut l = StateLayout::ins21();
        assert_eq!(l.len(), N_INS);
        assert_eq!(l.index(Block::AccelScale), Some(SA));
        assert_eq!(l.push(Block::TimeOffset), 21);
        assert_eq!(l.push(Block::TimeOffset), 21);
        assert_eq!(l.len(), 22);
    }
}
