//! What the forward pass records for the RTS smoother: one [`RtsRecord`] per
//! covariance epoch (docs/ALGORITHMS.md "Smoothing").
//!
//! A record holds the transitions of the covariance since the previous record
//! (propagation, added variance, state resets, composed into one Phi and one Q:
//! P^- = Phi P_prev^+ Phi^T + Q), the covariance after its updates and the sum of
//! the corrections they fed back. A record closes when the covariance moves on after an
//! update or later in time; changes at one time are composed. So the covariance at
//! an output epoch is the `p_post` of the record it belongs to.

use nalgebra::{DMatrix, DVector};

/// One covariance epoch of the forward filter.
#[derive(Clone, Debug, PartialEq)]
pub struct RtsRecord {
    /// IMU time of the epoch \[s\].
    pub t: f64,
    /// Transition from the previous record's updated error state to this record's
    /// prior one (`None`: identity; the first record has none).
    pub phi: Option<DMatrix<f64>>,
    /// Noise added by the transition (`None`: zero): the covariance before this
    /// record's updates is Phi P_prev^+ Phi^T + Q.
    pub q: Option<DMatrix<f64>>,
    /// Covariance after this record's updates.
    pub p_post: DMatrix<f64>,
    /// Sum of the corrections fed back at this record (zero without an update).
    pub dx: DVector<f64>,
    /// The transition is the filter's process model alone: no variance added, no
    /// state reset (re-admissions, gaps and re-initialisations are not). Noise
    /// identification (`crate::tuning`) learns the process noise from these only.
    pub propagated_only: bool,
}

impl RtsRecord {
    pub fn dim(&self) -> usize {
        self.p_post.nrows()
    }
}

/// A change of the covariance that is not an update.
pub(crate) enum Transition<'a> {
    /// P = Phi P Phi^T + Qd.
    Propagate(&'a DMatrix<f64>, &'a DMatrix<f64>),
    /// Variance `var` added to state `i` (Phi = I).
    AddVariance(usize, f64),
    /// State `i` re-initialised with variance `var`: uncorrelated with the rest (row
    /// i of Phi is zero).
    Reset(usize, f64),
}

struct Open {
    t: f64,
    phi: Option<DMatrix<f64>>,
    q: Option<DMatrix<f64>>,
    dx: DVector<f64>,
    updated: bool,
    propagated_only: bool,
}

impl Open {
    fn new(t: f64, n: usize) -> Self {
        Open {
            t,
            phi: None,
            q: None,
            dx: DVector::zeros(n),
            updated: false,
            propagated_only: true,
        }
    }
}

/// Builds the records as the filter runs; the driver drains the closed ones.
pub(crate) struct Recorder {
    open: Open,
    closed: Vec<RtsRecord>,
    count: u64,
}

impl Recorder {
    pub fn new(t0: f64, n: usize) -> Self {
        Recorder {
            open: Open::new(t0, n),
            closed: Vec::new(),
            count: 0,
        }
    }

    /// Index of the record the current epoch belongs to.
    pub fn current_index(&self) -> u64 {
        self.count
    }

    fn close(&mut self, p_now: &DMatrix<f64>, t_next: f64) {
        let n = p_now.nrows();
        let open = std::mem::replace(&mut self.open, Open::new(t_next, n));
        self.closed.push(RtsRecord {
            t: open.t,
            phi: open.phi,
            q: open.q,
            p_post: p_now.clone(),
            dx: open.dx,
            propagated_only: open.propagated_only,
        });
        self.count += 1;
    }

    /// Before the covariance `p_now` (at time `t`) undergoes `tr`.
    pub fn transition(&mut self, t: f64, tr: Transition<'_>, p_now: &DMatrix<f64>) {
        if self.open.updated || t > self.open.t {
            self.close(p_now, t);
        }
        let o = &mut self.open;
        o.t = t;
        let n = p_now.nrows();
        match tr {
            Transition::Propagate(phi, qd) => {
                // Composed: Q = Phi Q_before Phi^T + Qd.
                o.q = Some(match o.q.take() {
                    None => qd.clone(),
                    Some(q) => phi * q * phi.transpose() + qd,
                });
                o.phi = Some(match o.phi.take() {
                    None => phi.clone(),
                    Some(acc) => phi * acc,
                });
            }
            Transition::AddVariance(i, var) => {
                o.propagated_only = false;
                o.q.get_or_insert_with(|| DMatrix::zeros(n, n))[(i, i)] += var;
            }
            Transition::Reset(i, var) => {
                o.propagated_only = false;
                let phi = o.phi.get_or_insert_with(|| DMatrix::identity(n, n));
                phi.row_mut(i).fill(0.0);
                let q = o.q.get_or_insert_with(|| DMatrix::zeros(n, n));
                q.row_mut(i).fill(0.0);
                q.column_mut(i).fill(0.0);
                q[(i, i)] = var;
            }
        }
    }

    /// Sum of the corrections fed back so far at the open record.
    pub fn open_dx(&self) -> &DVector<f64> {
        &self.open.dx
    }

    /// An update was applied and `dx` fed back.
    pub fn applied(&mut self, dx: &DVector<f64>) {
        self.open.updated = true;
        self.open.dx += dx;
    }

    /// Close the last record (end of the run).
    pub fn finish(&mut self, p_now: &DMatrix<f64>) {
        let t = self.open.t;
        self.close(p_now, t);
    }

    /// The records closed since the last call.
    pub fn drain(&mut self) -> std::vec::Drain<'_, RtsRecord> {
        self.closed.drain(..)
    }
}
