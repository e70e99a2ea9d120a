//! The UBX keys of `[gnss]` (`gnss.format = "ubx"`): `ubx_source = "raw"` (the
//! default: RXM-RAWX + RXM-SFRBX through the GNSS layer, with every RINEX key and an
//! optional `nav` file adding ephemerides) or `"pvt"` (the receiver's NAV-PVT fixes,
//! loose coupling, none of the RINEX keys).

use std::path::{Path, PathBuf};

use navfuse_core::config::TightOptions;
use serde::{Deserialize, Serialize};

use super::error::{kerr, KResult};
use super::gnss::{rinex_key_set, TGnss};
use super::paths::{file_key, PathWriter};
use super::rinex;
use crate::input::UbxGnss;

/// `gnss.ubx_source`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(super) enum TUbxSource {
    Raw,
    Pvt,
}

/// `gnss.format = "ubx"`.
pub(super) fn convert(g: &TGnss, base: &Path) -> KResult<(UbxGnss, TightOptions)> {
    match g.ubx_source.unwrap_or(TUbxSource::Raw) {
        TUbxSource::Pvt => {
            if let Some(key) = rinex_key_set(g) {
                return Err(kerr(
                    key,
                    "applies only to raw observations: with gnss.ubx_source = \"pvt\" the receiver's fixes are used (set ubx_source = \"raw\")",
                ));
            }
            Ok((UbxGnss::Pvt, TightOptions::default()))
        }
        TUbxSource::Raw => {
            let nav = match g.nav.as_deref() {
                Some(n) => file_key(base, "gnss.nav", n)?,
                None => PathBuf::new(),
            };
            let (r, t) = rinex::convert_with_nav(g, base, nav)?;
            Ok((UbxGnss::Raw(r), t))
        }
    }
}

/// The UBX keys of `t` from `u` and `tight`.
pub(super) fn to_toml(u: &UbxGnss, tight: &TightOptions, t: &mut TGnss, w: &PathWriter) {
    match u {
        UbxGnss::Pvt => t.ubx_source = Some(TUbxSource::Pvt),
        UbxGnss::Raw(r) => {
            rinex::to_toml(r, tight, t, w);
            if u.extra_nav().is_none() {
                t.nav = None;
            }
            t.ubx_source = Some(TUbxSource::Raw);
        }
    }
}
