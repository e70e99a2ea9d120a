//! Tests of the RINEX observation reader and writer.

use super::*;

#[test]
fn ssi_table() {
    assert_eq!(ssi_from_cn0(5.0), 1);
    assert_eq!(ssi_from_cn0(12.0), 2);
    assert_eq!(ssi_from_cn0(17.9), 2);
    assert_eq!(ssi_from_cn0(18.0), 3);
    assert_eq!(ssi_from_cn0(45.0), 7);
    assert_eq!(ssi_from_cn0(53.9), 8);
    assert_eq!(ssi_from_cn0(54.0), 9);
    assert_eq!(ssi_from_cn0(70.0), 9);
}
