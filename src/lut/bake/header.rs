//! The header a baked table carries: its axes, channels, stack and the
//! bake check's figures.

use super::check::Check;
use super::grid::Grid;
use super::sweep::Prepared;
use crate::lut::axis::Axis;
use crate::lut::header::{
    version_for, BakeCheck, Channel, ColorInfo, ErrorInfo, Header, BAKE_CHECK_METRIC, COS_AXIS,
    FORMAT_NAME, THICKNESS_AXIS, WAVELENGTH_AXIS,
};
use crate::lut::sample::channel_names;
use crate::lut::{BakeSpec, Kind};

pub(super) fn header(
    spec: &BakeSpec,
    prep: &Prepared,
    coarse: &Grid,
    check: Option<&Check>,
    target: Option<f64>,
) -> Header {
    let channel_meaning = |name: &str| -> String {
        let (quantity, rest) = name.split_once('.').unwrap_or((name, ""));
        let what = if quantity == "reflectance" {
            "unpolarized reflectance"
        } else {
            "unpolarized transmittance (power into the substrate)"
        };
        match rest {
            "" => format!("{what} at the node's wavelength"),
            c => format!("{what}, linear sRGB {c} under D65 (a perfect reflector is 1)"),
        }
    };
    let mut axes = vec![
        Axis {
            name: THICKNESS_AXIS.into(),
            unit: "nm".into(),
            nodes: coarse.axes[0].nodes.clone(),
        },
        Axis {
            name: COS_AXIS.into(),
            unit: "1".into(),
            nodes: coarse.axes[1].nodes.clone(),
        },
    ];
    if spec.kind == Kind::Spectral {
        axes.push(Axis {
            name: WAVELENGTH_AXIS.into(),
            unit: "nm".into(),
            nodes: coarse.axes[2].nodes.clone(),
        });
    }
    let names = channel_names(spec.kind);
    Header {
        format: FORMAT_NAME.into(),
        version: version_for(spec.white),
        kind: spec.kind,
        x_axis: THICKNESS_AXIS.into(),
        y_axis: COS_AXIS.into(),
        y_blocks: (spec.kind == Kind::Spectral).then(|| WAVELENGTH_AXIS.into()),
        axes,
        channels: names
            .iter()
            .map(|n| Channel {
                name: (*n).into(),
                meaning: channel_meaning(n),
            })
            .collect(),
        precision: if spec.half { "f16" } else { "f32" }.into(),
        stack: spec.stack.clone(),
        layer: if spec.stack.layers.is_empty() {
            0
        } else {
            prep.layer
        },
        color: ColorInfo {
            white: spec.white,
            illuminant: spec.white.illuminant().into(),
            observer: "CIE 1931 2°".into(),
            space: "linear sRGB (ITU-R BT.709 primaries, D65 white)".into(),
            sampling: spec.sampling.to_string(),
        },
        error: ErrorInfo {
            target_max_abs: target,
            bake_check: check.map(|check| BakeCheck {
                metric: BAKE_CHECK_METRIC.into(),
                points: check.points,
                max_abs: check.max_channel.clone(),
                max_abs_all: check.max_all,
            }),
            validation: None,
        },
        tool: format!("irid {}", env!("CARGO_PKG_VERSION")),
        cache_key: spec.cache_key(),
    }
}
