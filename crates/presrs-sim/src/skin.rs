//! The foot, the PreSRS skin and its contact with the terrain (paper, sections II-III).
//!
//! Layers from the foot outwards: felt (subcutaneous, > 3 mm, conforming), the TekScan array (dermis),
//! a stiff silicone-rubber epidermis (> 1 mm). The array therefore measures the pressure on the felt.
//! Model, per frame of a stance:
//! 1. The foot's base is a rigid flat ellipse (48.3 x 52.1 mm) kept flat on the ground by the compliant
//!    ankle, at height `b0` with small tilts `(theta_x, theta_y)`; its rim is rounded by `rim_rounding_m`.
//! 2. At each sample point the terrain surface penetrates the skin by `d = s - base` (where positive).
//!    The felt (a Winkler foundation, `k_felt = E_felt / t_felt`) and the terrain's surface layer
//!    (`k_surface`, possibly yielding at `p_yield`) act in series: `p = min(k_eff d, p_yield)`.
//! 3. `(b0, theta_x, theta_y)` are solved (Newton's method with a line search on the convex contact
//!    energy) so that the integral of pressure equals the normal force of the dynamics and the centre of
//!    pressure is where the ankle's moment balance puts it.
//! 4. The stiff epidermis spreads each sensel's load over its neighbours: a plate on an elastic
//!    foundation has the characteristic length `lambda = (D / k_felt)^(1/4)`, `D = E h^3 / (12 (1 - nu^2))`;
//!    the spreading is a Gaussian of standard deviation `spread_factor * lambda`, normalised over the
//!    sensels under the foot so that the total force is preserved exactly.

use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError, param};
use crate::terrain::SurfacePatch;

/// The TekScan #5051 array and the foot on it (paper, sections II-III).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FootParams {
    /// Sensel rows and columns of the array (44 x 44).
    pub rows: usize,
    pub cols: usize,
    /// Sensel pitch, m (1.27 mm).
    pub pitch_m: f64,
    /// The foot's base: an ellipse of `length_m` along the direction of travel (columns) and `width_m`
    /// across it (rows): 52.1 mm x 48.3 mm = 41 x 38 sensels.
    pub length_m: f64,
    pub width_m: f64,
    /// Top-left sensel of the rectangle the ellipse is inscribed in: the paper keeps rows 0-37 and
    /// columns 3-43 (dropping the bottom 6 rows and the first 3 columns).
    pub first_row: usize,
    pub first_col: usize,
    /// Sample points per sensel along each axis (the terrain is finer than a sensel).
    pub subsamples: usize,
}

impl Default for FootParams {
    fn default() -> Self {
        Self {
            rows: 44,
            cols: 44,
            pitch_m: 1.27e-3,
            length_m: 52.1e-3,
            width_m: 48.3e-3,
            first_row: 0,
            first_col: 3,
            subsamples: 2,
        }
    }
}

/// Mechanical properties of the skin layers (assumptions within the paper's stated thicknesses).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SkinParams {
    /// Felt: compressive modulus (Pa) and thickness (m; paper: > 3 mm). Wool felt: ~0.5 MPa.
    pub felt_modulus_pa: f64,
    pub felt_thickness_m: f64,
    /// Silicone-rubber epidermis: Young's modulus (Pa; "hard" silicone, Shore ~60A: ~3 MPa), thickness
    /// (m; paper: > 1 mm) and Poisson's ratio.
    pub epidermis_modulus_pa: f64,
    pub epidermis_thickness_m: f64,
    pub epidermis_poisson: f64,
    /// Gaussian spreading width as a fraction of the plate's characteristic length (approximation of
    /// the central lobe of the plate-on-foundation deflection kernel).
    pub spread_factor: f64,
    /// How far the rounded rim of the foot's base rises above its centre, m.
    pub rim_rounding_m: f64,
}

impl Default for SkinParams {
    fn default() -> Self {
        Self {
            felt_modulus_pa: 0.5e6,
            felt_thickness_m: 3.2e-3,
            epidermis_modulus_pa: 3.0e6,
            epidermis_thickness_m: 1.2e-3,
            epidermis_poisson: 0.49,
            spread_factor: 0.5,
            rim_rounding_m: 0.15e-3,
        }
    }
}

impl SkinParams {
    /// Winkler modulus of the felt, Pa/m.
    pub fn felt_stiffness_pa_per_m(&self) -> f64 {
        self.felt_modulus_pa / self.felt_thickness_m
    }

    /// Characteristic length of the epidermis plate on the felt, m.
    pub fn plate_length_m(&self) -> f64 {
        let h = self.epidermis_thickness_m;
        let d = self.epidermis_modulus_pa * h * h * h
            / (12.0 * (1.0 - self.epidermis_poisson * self.epidermis_poisson));
        (d / self.felt_stiffness_pa_per_m()).powf(0.25)
    }

    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("skin.felt_modulus_pa", self.felt_modulus_pa),
            ("skin.felt_thickness_m", self.felt_thickness_m),
            ("skin.epidermis_modulus_pa", self.epidermis_modulus_pa),
            ("skin.epidermis_thickness_m", self.epidermis_thickness_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(param(name, format!("must be positive, got {v}")));
            }
        }
        if !(0.0..0.5).contains(&self.epidermis_poisson) {
            return Err(param("skin.epidermis_poisson", "must be in [0, 0.5)"));
        }
        if !(self.spread_factor.is_finite() && self.spread_factor >= 0.0) {
            return Err(param("skin.spread_factor", "must be >= 0"));
        }
        Ok(())
    }
}

/// The foot's sample points and the spreading kernel, precomputed once.
#[derive(Clone, Debug)]
pub struct Foot {
    pub params: FootParams,
    /// Sample points `(x, y)` in metres (x forward = increasing column, y left = decreasing row).
    pub points: Vec<(f64, f64)>,
    /// Sensel (row-major index) of each sample point.
    point_sensel: Vec<usize>,
    /// Rim rounding of each sample point, m (subtracted from the penetration).
    rim_m: Vec<f64>,
    /// Area of one sample point, m^2.
    point_area_m2: f64,
    /// Sensels under the foot (any sample point inside the ellipse).
    pub under_foot: Vec<bool>,
    /// Semi-axes of the ellipse, m (x, y).
    pub semi_axes_m: (f64, f64),
    /// Spreading kernel: for each sensel under the foot, (target sensel, weight) with weights summing to 1.
    spread: Vec<Vec<(usize, f64)>>,
    felt_k: f64,
}

/// The contact state solved for one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactState {
    /// Base height (m), and tilts (rad) about the y and x axes.
    pub base_m: f64,
    pub tilt_x: f64,
    pub tilt_y: f64,
}

impl Foot {
    pub fn new(params: FootParams, skin: &SkinParams) -> Result<Self> {
        skin.validate()?;
        let p = &params;
        if p.rows == 0 || p.cols == 0 || p.subsamples == 0 || p.pitch_m.is_nan() || p.pitch_m <= 0.0
        {
            return Err(param(
                "foot",
                "rows, cols, subsamples and pitch must be positive",
            ));
        }
        let ax = 0.5 * p.length_m;
        let ay = 0.5 * p.width_m;
        // Ellipse centre in sensel coordinates (continuous: sensel (r, c) covers [c, c+1) x [r, r+1)).
        let c_col = p.first_col as f64 + p.length_m / p.pitch_m * 0.5;
        let c_row = p.first_row as f64 + p.width_m / p.pitch_m * 0.5;
        if c_col + ax / p.pitch_m > p.cols as f64 + 1.0
            || c_row + ay / p.pitch_m > p.rows as f64 + 1.0
        {
            return Err(param(
                "foot",
                "the foot's base does not fit on the sensor array",
            ));
        }
        let n = p.subsamples;
        let mut points = Vec::new();
        let mut point_sensel = Vec::new();
        let mut rim_m = Vec::new();
        let mut under_foot = vec![false; p.rows * p.cols];
        for r in 0..p.rows {
            for c in 0..p.cols {
                for i in 0..n {
                    for j in 0..n {
                        let col = c as f64 + (j as f64 + 0.5) / n as f64;
                        let row = r as f64 + (i as f64 + 0.5) / n as f64;
                        let x = (col - c_col) * p.pitch_m;
                        let y = (c_row - row) * p.pitch_m;
                        let rho2 = (x / ax).powi(2) + (y / ay).powi(2);
                        if rho2 <= 1.0 {
                            points.push((x, y));
                            point_sensel.push(r * p.cols + c);
                            // Rounded rim: the last ~15 % of the radius curls up.
                            let rho = rho2.sqrt();
                            let edge = ((rho - 0.85) / 0.15).max(0.0);
                            rim_m.push(skin.rim_rounding_m * edge * edge);
                            under_foot[r * p.cols + c] = true;
                        }
                    }
                }
            }
        }
        let sigma = skin.spread_factor * skin.plate_length_m() / p.pitch_m;
        let radius = (3.0 * sigma).ceil() as isize;
        let mut spread = vec![Vec::new(); p.rows * p.cols];
        for r in 0..p.rows as isize {
            for c in 0..p.cols as isize {
                let src = r as usize * p.cols + c as usize;
                if !under_foot[src] {
                    continue;
                }
                let mut list = Vec::new();
                let mut total = 0.0;
                for dr in -radius..=radius {
                    for dc in -radius..=radius {
                        let (rr, cc) = (r + dr, c + dc);
                        if rr < 0 || cc < 0 || rr >= p.rows as isize || cc >= p.cols as isize {
                            continue;
                        }
                        let dst = rr as usize * p.cols + cc as usize;
                        if !under_foot[dst] {
                            continue;
                        }
                        let w = if sigma > 0.0 {
                            (-((dr * dr + dc * dc) as f64) / (2.0 * sigma * sigma)).exp()
                        } else if dr == 0 && dc == 0 {
                            1.0
                        } else {
                            0.0
                        };
                        if w > 1e-6 {
                            list.push((dst, w));
                            total += w;
                        }
                    }
                }
                for item in &mut list {
                    item.1 /= total;
                }
                spread[src] = list;
            }
        }
        let point_area_m2 = (p.pitch_m / n as f64).powi(2);
        Ok(Self {
            params,
            points,
            point_sensel,
            rim_m,
            point_area_m2,
            under_foot,
            semi_axes_m: (ax, ay),
            spread,
            felt_k: skin.felt_stiffness_pa_per_m(),
        })
    }

    /// Area of one sensel, m^2.
    pub fn sensel_area_m2(&self) -> f64 {
        self.params.pitch_m * self.params.pitch_m
    }

    /// Effective local stiffness (felt in series with the surface) at each sample point, Pa/m.
    pub fn effective_stiffness(&self, patch: &SurfacePatch) -> Vec<f64> {
        patch
            .stiffness_pa_per_m
            .iter()
            .map(|&ks| {
                if ks.is_infinite() {
                    self.felt_k
                } else {
                    1.0 / (1.0 / self.felt_k + 1.0 / ks)
                }
            })
            .collect()
    }

    /// Solves the contact for normal force `force_n` (N) with the centre of pressure at `cop_m` (m, foot
    /// frame; clamped to 60 % of the semi-axes), and returns the pressure image (Pa per sensel,
    /// `rows * cols`, row-major) after the epidermis spreading. `warm` is a starting guess and receives
    /// the solution.
    pub fn pressure_image(
        &self,
        patch: &SurfacePatch,
        k_eff: &[f64],
        force_n: f64,
        cop_m: (f64, f64),
        warm: &mut Option<ContactState>,
    ) -> Result<Vec<f64>> {
        let grid_len = self.params.rows * self.params.cols;
        let mut image = vec![0.0; grid_len];
        if force_n <= 0.0 {
            return Ok(image);
        }
        let (ax, ay) = self.semi_axes_m;
        let cop = (
            cop_m.0.clamp(-0.6 * ax, 0.6 * ax),
            cop_m.1.clamp(-0.6 * ay, 0.6 * ay),
        );
        let surface: Vec<f64> = patch
            .height_m
            .iter()
            .zip(&self.rim_m)
            .map(|(h, rim)| h - rim)
            .collect();
        // Yield: the plastic cap must leave enough capacity to carry the force.
        let capacity: f64 = patch.yield_pa.iter().map(|y| y * self.point_area_m2).sum();
        // With a fully plastic contact the pressure is uniform and cannot carry a moment: keep the
        // capacity at least twice the force (the clay stiffens as it is compacted).
        let yield_scale = if capacity < 2.0 * force_n {
            2.0 * force_n / capacity
        } else {
            1.0
        };
        let solve = |start, cop| {
            solve_contact(
                &self.points,
                &surface,
                k_eff,
                &patch.yield_pa,
                yield_scale,
                self.point_area_m2,
                force_n,
                cop,
                start,
            )
        };
        // A warm start from the previous frame is usually a few Newton steps away; fall back to cold.
        // If the CoP asked for cannot be reached (a contact too plastic or too sparse to carry the
        // moment), fall back to a CoP halfway to the centre, then to the centre.
        let state = match solve(*warm, cop) {
            Ok(state) => state,
            Err(_) => match solve(None, cop) {
                Ok(state) => state,
                Err(_) => match solve(None, (0.5 * cop.0, 0.5 * cop.1)) {
                    Ok(state) => state,
                    Err(_) => solve(None, (0.0, 0.0))?,
                },
            },
        };
        *warm = Some(state);
        // Sensel forces.
        let mut sensel_force = vec![0.0; grid_len];
        for (i, &(x, y)) in self.points.iter().enumerate() {
            let d = surface[i] - state.base_m - state.tilt_x * x - state.tilt_y * y;
            if d > 0.0 {
                let p = (k_eff[i] * d).min(patch.yield_pa[i] * yield_scale);
                sensel_force[self.point_sensel[i]] += p * self.point_area_m2;
            }
        }
        // Epidermis spreading (conserves the total exactly).
        let area = self.sensel_area_m2();
        for (src, f) in sensel_force.iter().enumerate() {
            if *f == 0.0 {
                continue;
            }
            for &(dst, w) in &self.spread[src] {
                image[dst] += f * w / area;
            }
        }
        Ok(image)
    }
}

/// Pressure and its derivative for penetration `d` (m) with stiffness `k` (Pa/m) and yield `py` (Pa);
/// also the contact energy density.
#[inline]
fn law(d: f64, k: f64, py: f64) -> (f64, f64, f64) {
    if d <= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    let dy = py / k;
    if d < dy {
        (k * d, k, 0.5 * k * d * d)
    } else {
        (py, 0.0, py * d - 0.5 * py * dy)
    }
}

/// Minimises the convex contact energy `sum(w psi(d_i)) + F b0 + F cop_x theta_x + F cop_y theta_y`
/// whose stationarity conditions are: sum of pressure forces = F, first moments = F * cop.
#[allow(clippy::too_many_arguments)]
fn solve_contact(
    points: &[(f64, f64)],
    surface: &[f64],
    k: &[f64],
    yield_pa: &[f64],
    yield_scale: f64,
    w: f64,
    force: f64,
    cop: (f64, f64),
    warm: Option<ContactState>,
) -> Result<ContactState> {
    let n = points.len();
    if n == 0 {
        return Err(SimError::Contact("no sample points under the foot".into()));
    }
    let eval = |u: [f64; 3], want_hessian: bool| {
        let mut energy = force * u[0] + force * cop.0 * u[1] + force * cop.1 * u[2];
        let mut grad = [force, force * cop.0, force * cop.1];
        let mut hess = [[0.0; 3]; 3];
        for i in 0..n {
            let (x, y) = points[i];
            let d = surface[i] - u[0] - u[1] * x - u[2] * y;
            if d <= 0.0 {
                continue;
            }
            let (p, dp, e) = law(d, k[i], yield_pa[i] * yield_scale);
            energy += w * e;
            let g = [1.0, x, y];
            for a in 0..3 {
                grad[a] -= w * p * g[a];
            }
            if want_hessian && dp > 0.0 {
                for a in 0..3 {
                    for b in 0..3 {
                        hess[a][b] += w * dp * g[a] * g[b];
                    }
                }
            }
        }
        (energy, grad, hess)
    };
    let mut u = match warm {
        Some(s) => [s.base_m, s.tilt_x, s.tilt_y],
        None => {
            // Full contact guess.
            let kw: f64 = k.iter().sum::<f64>() * w;
            let ks: f64 = k.iter().zip(surface).map(|(k, s)| k * s).sum::<f64>() * w;
            [(ks - force) / kw, 0.0, 0.0]
        }
    };
    // Force to 1 ppm, moments to 1 ppm of the force times 10 mm: far inside the 1 % requirement.
    let force_tol = 1e-6 * force;
    let moment_tol = 1e-6 * force * 0.01;
    for _ in 0..200 {
        let (e0, g, h) = eval(u, true);
        if g[0].abs() < force_tol && g[1].abs() < moment_tol && g[2].abs() < moment_tol {
            return Ok(ContactState {
                base_m: u[0],
                tilt_x: u[1],
                tilt_y: u[2],
            });
        }
        // Newton direction (regularised); if the Hessian is empty, lower the foot.
        let step = if h[0][0] > 0.0 {
            let mut hr = h;
            let scale = h[0][0];
            hr[0][0] += 1e-12 * scale;
            hr[1][1] += 1e-12 * scale * 1e-4 + 1e-9 * scale * 1e-4;
            hr[2][2] += 1e-12 * scale * 1e-4 + 1e-9 * scale * 1e-4;
            solve3(hr, [-g[0], -g[1], -g[2]])
        } else {
            None
        };
        let dir = match step {
            Some(s) if s.iter().all(|v| v.is_finite()) => s,
            _ => [-1e-4, 0.0, 0.0],
        };
        let slope = g[0] * dir[0] + g[1] * dir[1] + g[2] * dir[2];
        let dir = if slope >= 0.0 {
            [-g[0] * 1e-12, -g[1] * 1e-12, -g[2] * 1e-12]
        } else {
            dir
        };
        let slope = g[0] * dir[0] + g[1] * dir[1] + g[2] * dir[2];
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..60 {
            let trial = [u[0] + t * dir[0], u[1] + t * dir[1], u[2] + t * dir[2]];
            let (e1, ..) = eval(trial, false);
            if e1 <= e0 + 1e-4 * t * slope && trial != u {
                u = trial;
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            // Converged to machine precision in energy; accept if the force is close.
            let (_, g, _) = eval(u, false);
            if g[0].abs() < 1e-4 * force {
                return Ok(ContactState {
                    base_m: u[0],
                    tilt_x: u[1],
                    tilt_y: u[2],
                });
            }
            return Err(SimError::Contact(format!(
                "line search failed (force residual {:.3e} N)",
                g[0]
            )));
        }
    }
    let (_, g, _) = eval(u, false);
    Err(SimError::Contact(format!(
        "no convergence in 200 Newton steps (force {force:.4e} N, centre of pressure {cop:?} m, \
         residuals {g:?})"
    )))
}

fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if det.abs() < 1e-300 || !det.is_finite() {
        return None;
    }
    let mut out = [0.0; 3];
    for (col, o) in out.iter_mut().enumerate() {
        let mut m = a;
        for row in 0..3 {
            m[row][col] = b[row];
        }
        let d = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        *o = d / det;
    }
    Some(out)
}
