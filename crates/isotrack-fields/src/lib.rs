//! # isotrack-fields
//!
//! Scalar fields behind the [`ScalarField`] / [`FieldDerivatives`] traits of `isotrack-core`.
//!
//! * [`analytic`]: closed-form fields with exact gradient and Hessian: the paper's circular field
//!   [`RadialExp`], a sum of anisotropic Gaussian plumes [`GaussianPlumes`] (a PM2.5-like
//!   multi-source map with non-circular isolines), and a [`LinearRamp`]; [`AnalyticField`] wraps
//!   them with an optional rectangular domain outside which the field has no value.
//! * [`grid`]: regular grids ([`grid::Grid2`]) with bilinear or C1 bicubic interpolation and
//!   analytic derivatives ([`grid::GridField`]).
//! * [`io`]: grid loaders (CSV, NumPy `.npy`, ESRI ASCII grid, GeoTIFF, NetCDF).
//! * [`georef`]: from file coordinates (projected or longitude/latitude) to local metres.
//! * [`stations`]: fields from scattered stations (inverse-distance weighting, ordinary kriging).
//! * [`puff`]: a plume of puffs in wind (after Farrell et al., 2002), simplified to 2-D.
//! * [`isoline`]: the true isoline `F = s_d`, for the distance metric.
#![deny(missing_docs)]

pub mod analytic;
pub mod georef;
pub mod grid;
pub mod io;
pub mod isoline;
pub mod puff;
pub mod stations;

pub use analytic::{AnalyticField, AnalyticKind, GaussianPlumes, LinearRamp, Plume, RadialExp};
pub use isotrack_core::{FieldDerivatives, ScalarField};
