//! Embedded Runge–Kutta pairs: two solutions of different orders from the same stages,
//! whose difference estimates the local error for step-size control
//! ([`crate::control::PiController`]), and a continuous extension (dense output) of the
//! step. With a fixed step they are ordinary explicit methods of the higher order.
//!
//! # References
//! - J. R. Dormand, P. J. Prince, "A family of embedded Runge–Kutta formulae", J. Comput.
//!   Appl. Math. 6 (1980) 19–26.
//! - P. J. Prince, J. R. Dormand, "High order embedded Runge–Kutta formulae", J. Comput.
//!   Appl. Math. 7 (1981) 67–75.
//! - E. Hairer, S. P. Nørsett, G. Wanner, *Solving ODEs I*, §II.4, §II.5, §II.6 (dense
//!   output) and §II.10 (the DOP853 code and its error estimator).

use super::{Method, Requirement, Scheme, Stepper};
use crate::Error;
use crate::checkpoint::{Reader, Snapshot, Words};
use crate::control::{ControlParams, DOP853_CONTROL, DOPRI5_CONTROL};
use crate::observe::DenseStep;
use crate::system::System;

/// How a pair estimates its local error from the stages (e = h Σ eᵢ kᵢ).
#[derive(Debug, Clone, Copy)]
pub enum ErrorEstimate {
    /// One estimate, the propagated minus the embedded solution; its scaled RMS norm
    /// (Hairer, Nørsett, Wanner (4.11)) is the error.
    Single {
        /// Coefficients eᵢ = bᵢ − b̂ᵢ.
        e: &'static [f64],
    },
    /// DOP853's two estimates, of orders 5 and 3, combined as ‖e₅‖² / √(‖e₅‖² + 0.01 ‖e₃‖²):
    /// asymptotically of order 8 like the method, yet reliable at large steps where the
    /// order-5 estimate alone can be too small (Hairer, Nørsett, Wanner §II.10).
    Dop853 {
        /// Coefficients of the order-5 estimate.
        e5: &'static [f64],
        /// Coefficients of the order-3 estimate.
        e3: &'static [f64],
    },
}

/// The tableau of an embedded pair with its dense output.
///
/// Stages are numbered as the rows of `a`: first the `stages` an attempted step needs, then
/// (if `new_point` = `stages`) f(t + h, y₁), then the extra stages of the dense output. Every
/// pair here is "first same as last": stage `new_point` is f(t + h, y₁), the next step's
/// first stage.
#[derive(Debug, Clone, Copy)]
pub struct EmbeddedTableau {
    /// Nodes cᵢ, for every row of `a`.
    pub c: &'static [f64],
    /// Strictly lower triangular coefficients aᵢⱼ (row i has at most i entries).
    pub a: &'static [&'static [f64]],
    /// Weights of the propagated solution (order [`Method::order`]), over the first stages.
    pub b: &'static [f64],
    /// How the local error is estimated.
    pub error: ErrorEstimate,
    /// Order of the error estimate as the controller sees it.
    pub error_order: u32,
    /// Stages an attempted step evaluates.
    pub stages: usize,
    /// The stage that is f(t + h, y₁) (its row of `a` is `b`).
    pub new_point: usize,
    /// Dense output: y(t + θh) = r₀ + θ(r₁ + (1−θ)(r₂ + θ(r₃ + (1−θ)(r₄ + θ(r₅ + …))))) with
    /// r₀ = y₀, r₁ = y₁ − y₀, r₂ = h k₁ − r₁, r₃ = r₁ − h f(t + h, y₁) − r₂ (the cubic
    /// Hermite part), and r₄, r₅, … = h Σ dᵢ kᵢ, one row of d each (Hairer, Nørsett, Wanner
    /// §II.6).
    pub dense: &'static [&'static [f64]],
    /// Order of the dense output: its error within a step is O(h^(order + 1)).
    pub dense_order: u32,
    /// The step-size controller's parameters.
    pub control: &'static ControlParams,
}

impl EmbeddedTableau {
    /// Number of polynomial coefficients rᵢ of the dense output.
    pub fn dense_terms(&self) -> usize {
        4 + self.dense.len()
    }
}

/// Dormand–Prince 5(4): 7 stages, 6 evaluations per accepted step (FSAL), order 5 with an
/// order-4 error estimate and Shampine's order-4 dense output at no extra evaluation.
///
/// Requirements: none.
///
/// # References
/// Dormand & Prince (1980); Hairer, Nørsett, Wanner, *Solving ODEs I*, Table II.5.2, and the
/// dense output of their DOPRI5 code (L. F. Shampine, Math. Comp. 46 (1986) 135–150).
pub static DOPRI5: Method = Method {
    name: "dopri5",
    title: "Dormand-Prince 5(4)",
    order: 5,
    requirement: Requirement::Any,
    symplectic: false,
    symmetric: false,
    description: "adaptive Dormand-Prince 5(4) with a PI step-size controller (tolerances rtol, atol); 6 evaluations per step",
    reference: "Dormand & Prince, J. Comput. Appl. Math. 6 (1980) 19; Hairer, Norsett, Wanner, Table II.5.2",
    scheme: Scheme::Embedded(&EmbeddedTableau {
        c: &[0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
        a: &[
            &[],
            &[1.0 / 5.0],
            &[3.0 / 40.0, 9.0 / 40.0],
            &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
            &[19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0],
            &[9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0],
            &[35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
        ],
        b: &[35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0],
        // b − b̂, with b̂ = (5179/57600, 0, 7571/16695, 393/640, −92097/339200, 187/2100, 1/40).
        error: ErrorEstimate::Single {
            e: &[
                71.0 / 57600.0,
                0.0,
                -71.0 / 16695.0,
                71.0 / 1920.0,
                -17253.0 / 339200.0,
                22.0 / 525.0,
                -1.0 / 40.0,
            ],
        },
        error_order: 4,
        stages: 7,
        new_point: 6,
        dense: &[&[
            -12715105075.0 / 11282082432.0,
            0.0,
            87487479700.0 / 32700410799.0,
            -10690763975.0 / 1880347072.0,
            701980252875.0 / 199316789632.0,
            -1453857185.0 / 822651844.0,
            69997945.0 / 29380423.0,
        ]],
        dense_order: 4,
        control: &DOPRI5_CONTROL,
    }),
};

/// Dormand–Prince 8(5,3), Hairer's DOP853: 12 stages, 12 evaluations per accepted step
/// (FSAL), order 8 with error estimates of orders 5 and 3, and an order-7 dense output
/// from 3 more evaluations per step (only when a step's interior is needed: events).
///
/// Requirements: none.
///
/// # References
/// Prince & Dormand (1981); Hairer, Nørsett, Wanner, *Solving ODEs I*, §II.10 and the
/// coefficients of their DOP853 code (version of 2004).
#[allow(clippy::excessive_precision)] // the coefficients as published, to 30 digits
pub static DOP853: Method = Method {
    name: "dop853",
    title: "Dormand-Prince 8(5,3)",
    order: 8,
    requirement: Requirement::Any,
    symplectic: false,
    symmetric: false,
    description: "adaptive Dormand-Prince 8(5,3) (Hairer's DOP853), order-7 dense output; for tight tolerances",
    reference: "Prince & Dormand, J. Comput. Appl. Math. 7 (1981) 67; Hairer, Norsett, Wanner, §II.10 (DOP853)",
    scheme: Scheme::Embedded(&EmbeddedTableau {
        c: &[
            0.0,
            0.526001519587677318785587544488e-01,
            0.789002279381515978178381316732e-01,
            0.118350341907227396726757197510e+00,
            0.281649658092772603273242802490e+00,
            0.333333333333333333333333333333e+00,
            0.25e+00,
            0.307692307692307692307692307692e+00,
            0.651282051282051282051282051282e+00,
            0.6e+00,
            0.857142857142857142857142857142e+00,
            1.0,
            1.0,
            0.1,
            0.2,
            0.777777777777777777777777777778e+00,
        ],
        a: &[
            &[],
            &[5.26001519587677318785587544488e-2],
            &[1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2],
            &[2.95875854768068491816892993775e-2, 0.0, 8.87627564304205475450678981324e-2],
            &[
                2.41365134159266685502369798665e-1,
                0.0,
                -8.84549479328286085344864962717e-1,
                9.24834003261792003115737966543e-1,
            ],
            &[
                3.7037037037037037037037037037e-2,
                0.0,
                0.0,
                1.70828608729473871279604482173e-1,
                1.25467687566822425016691814123e-1,
            ],
            &[
                3.7109375e-2,
                0.0,
                0.0,
                1.70252211019544039314978060272e-1,
                6.02165389804559606850219397283e-2,
                -1.7578125e-2,
            ],
            &[
                3.70920001185047927108779319836e-2,
                0.0,
                0.0,
                1.70383925712239993810214054705e-1,
                1.07262030446373284651809199168e-1,
                -1.53194377486244017527936158236e-2,
                8.27378916381402288758473766002e-3,
            ],
            &[
                6.24110958716075717114429577812e-1,
                0.0,
                0.0,
                -3.36089262944694129406857109825e0,
                -8.68219346841726006818189891453e-1,
                2.75920996994467083049415600797e1,
                2.01540675504778934086186788979e1,
                -4.34898841810699588477366255144e1,
            ],
            &[
                4.77662536438264365890433908527e-1,
                0.0,
                0.0,
                -2.48811461997166764192642586468e0,
                -5.90290826836842996371446475743e-1,
                2.12300514481811942347288949897e1,
                1.52792336328824235832596922938e1,
                -3.32882109689848629194453265587e1,
                -2.03312017085086261358222928593e-2,
            ],
            &[
                -9.3714243008598732571704021658e-1,
                0.0,
                0.0,
                5.18637242884406370830023853209e0,
                1.09143734899672957818500254654e0,
                -8.14978701074692612513997267357e0,
                -1.85200656599969598641566180701e1,
                2.27394870993505042818970056734e1,
                2.49360555267965238987089396762e0,
                -3.0467644718982195003823669022e0,
            ],
            &[
                2.27331014751653820792359768449e0,
                0.0,
                0.0,
                -1.05344954667372501984066689879e1,
                -2.00087205822486249909675718444e0,
                -1.79589318631187989172765950534e1,
                2.79488845294199600508499808837e1,
                -2.85899827713502369474065508674e0,
                -8.87285693353062954433549289258e0,
                1.23605671757943030647266201528e1,
                6.43392746015763530355970484046e-1,
            ],
            // Stage 13: f(t + h, y₁), evaluated once the step is accepted.
            DOP853_B,
            // Stages 14–16: for the dense output only.
            &[
                5.61675022830479523392909219681e-2,
                0.0,
                0.0,
                0.0,
                0.0,
                0.0,
                2.53500210216624811088794765333e-1,
                -2.46239037470802489917441475441e-1,
                -1.24191423263816360469010140626e-1,
                1.5329179827876569731206322685e-1,
                8.20105229563468988491666602057e-3,
                7.56789766054569976138603589584e-3,
                -8.298e-3,
            ],
            &[
                3.18346481635021405060768473261e-2,
                0.0,
                0.0,
                0.0,
                0.0,
                2.83009096723667755288322961402e-2,
                5.35419883074385676223797384372e-2,
                -5.49237485713909884646569340306e-2,
                0.0,
                0.0,
                -1.08347328697249322858509316994e-4,
                3.82571090835658412954920192323e-4,
                -3.40465008687404560802977114492e-4,
                1.41312443674632500278074618366e-1,
            ],
            &[
                -4.28896301583791923408573538692e-1,
                0.0,
                0.0,
                0.0,
                0.0,
                -4.69762141536116384314449447206e0,
                7.68342119606259904184240953878e0,
                4.06898981839711007970213554331e0,
                3.56727187455281109270669543021e-1,
                0.0,
                0.0,
                0.0,
                -1.39902416515901462129418009734e-3,
                2.9475147891527723389556272149e0,
                -9.15095847217987001081870187138e0,
            ],
        ],
        b: DOP853_B,
        error: ErrorEstimate::Dop853 {
            e5: &[
                0.1312004499419488073250102996e-01,
                0.0,
                0.0,
                0.0,
                0.0,
                -0.1225156446376204440720569753e+01,
                -0.4957589496572501915214079952e+00,
                0.1664377182454986536961530415e+01,
                -0.3503288487499736816886487290e+00,
                0.3341791187130174790297318841e+00,
                0.8192320648511571246570742613e-01,
                -0.2235530786388629525884427845e-01,
            ],
            // b − b̂₃, where b̂₃ has weights 0.244094488188976377952755905512 on stage 1,
            // 0.733846688281611857341361741547 on 9 and 0.220588235294117647058823529412e-1
            // on 12.
            e3: &[
                5.42937341165687622380535766363e-2 - 0.244094488188976377952755905512e+00,
                0.0,
                0.0,
                0.0,
                0.0,
                4.45031289275240888144113950566e0,
                1.89151789931450038304281599044e0,
                -5.8012039600105847814672114227e0,
                3.1116436695781989440891606237e-1 - 0.733846688281611857341361741547e+00,
                -1.52160949662516078556178806805e-1,
                2.01365400804030348374776537501e-1,
                4.47106157277725905176885569043e-2 - 0.220588235294117647058823529412e-01,
            ],
        },
        error_order: 7,
        stages: 12,
        new_point: 12,
        dense: &[
            &[
                -0.84289382761090128651353491142e+01,
                0.0,
                0.0,
                0.0,
                0.0,
                0.56671495351937776962531783590e+00,
                -0.30689499459498916912797304727e+01,
                0.23846676565120698287728149680e+01,
                0.21170345824450282767155149946e+01,
                -0.87139158377797299206789907490e+00,
                0.22404374302607882758541771650e+01,
                0.63157877876946881815570249290e+00,
                -0.88990336451333310820698117400e-01,
                0.18148505520854727256656404962e+02,
                -0.91946323924783554000451984436e+01,
                -0.44360363875948939664310572000e+01,
            ],
            &[
                0.10427508642579134603413151009e+02,
                0.0,
                0.0,
                0.0,
                0.0,
                0.24228349177525818288430175319e+03,
                0.16520045171727028198505394887e+03,
                -0.37454675472269020279518312152e+03,
                -0.22113666853125306036270938578e+02,
                0.77334326684722638389603898808e+01,
                -0.30674084731089398182061213626e+02,
                -0.93321305264302278729567221706e+01,
                0.15697238121770843886131091075e+02,
                -0.31139403219565177677282850411e+02,
                -0.93529243588444783865713862664e+01,
                0.35816841486394083752465898540e+02,
            ],
            &[
                0.19985053242002433820987653617e+02,
                0.0,
                0.0,
                0.0,
                0.0,
                -0.38703730874935176555105901742e+03,
                -0.18917813819516756882830838328e+03,
                0.52780815920542364900561016686e+03,
                -0.11573902539959630126141871134e+02,
                0.68812326946963000169666922661e+01,
                -0.10006050966910838403183860980e+01,
                0.77771377980534432092869265740e+00,
                -0.27782057523535084065932004339e+01,
                -0.60196695231264120758267380846e+02,
                0.84320405506677161018159903784e+02,
                0.11992291136182789328035130030e+02,
            ],
            &[
                -0.25693933462703749003312586129e+02,
                0.0,
                0.0,
                0.0,
                0.0,
                -0.15418974869023643374053993627e+03,
                -0.23152937917604549567536039109e+03,
                0.35763911791061412378285349910e+03,
                0.93405324183624310003907691704e+02,
                -0.37458323136451633156875139351e+02,
                0.10409964950896230045147246184e+03,
                0.29840293426660503123344363579e+02,
                -0.43533456590011143754432175058e+02,
                0.96324553959188282948394950600e+02,
                -0.39177261675615439165231486172e+02,
                -0.14972683625798562581422125276e+03,
            ],
        ],
        dense_order: 7,
        control: &DOP853_CONTROL,
    }),
};

/// DOP853's weights b over its 12 stages.
#[allow(clippy::excessive_precision)]
const DOP853_B: &[f64] = &[
    5.42937341165687622380535766363e-2,
    0.0,
    0.0,
    0.0,
    0.0,
    4.45031289275240888144113950566e0,
    1.89151789931450038304281599044e0,
    -5.8012039600105847814672114227e0,
    3.1116436695781989440891606237e-1,
    -1.52160949662516078556178806805e-1,
    2.01365400804030348374776537501e-1,
    4.47106157277725905176885569043e-2,
];

/// Steps an embedded pair; owns its stage buffers, the candidate, its error estimates and
/// the dense-output coefficients of the last accepted step.
#[derive(Debug, Clone)]
pub struct EmbeddedRk {
    tableau: &'static EmbeddedTableau,
    /// Its stages' forms, the dense output's included.
    plan: super::explicit_rk::Plan,
    k: Vec<f64>,
    stage: Vec<f64>,
    /// The candidate solution of the last attempt.
    candidate: Vec<f64>,
    /// The error estimate(s) of the last attempt, h Σ eᵢ kᵢ (two for DOP853, one after
    /// the other).
    error: Vec<f64>,
    /// k₁ holds f(t, y) for this (t, y) from the previous accepted step.
    first_stage: Option<f64>,
    /// Coefficients r₀, r₁, … of the dense output, one row of `dim` each.
    dense: Vec<f64>,
    /// (t₀, h) of the step `dense` describes.
    dense_step: Option<(f64, f64)>,
}

impl EmbeddedRk {
    /// A stepper for systems of dimension `dim`.
    pub fn new(tableau: &'static EmbeddedTableau, dim: usize) -> Self {
        assert!(tableau.b.len() <= tableau.stages && tableau.new_point <= tableau.stages);
        EmbeddedRk {
            tableau,
            plan: super::explicit_rk::plan(tableau.a),
            k: vec![0.0; tableau.a.len() * dim],
            stage: vec![0.0; dim],
            candidate: vec![0.0; dim],
            error: vec![0.0; 2 * dim],
            first_stage: None,
            dense: vec![0.0; tableau.dense_terms() * dim],
            dense_step: None,
        }
    }

    /// Tries a step from (t, y) of size h: computes the candidate and its error estimate,
    /// leaving `y` unchanged.
    pub fn attempt<S: System + ?Sized>(&mut self, system: &S, t: f64, h: f64, y: &[f64]) {
        let tab = self.tableau;
        let n = y.len();
        let first = usize::from(self.first_stage == Some(t));
        let (a, c) = (&tab.a[..tab.stages], &tab.c[..tab.stages]);
        let mut f = |t: f64, y: &[f64], dydt: &mut [f64]| system.rhs(t, y, dydt);
        super::explicit_rk::explicit_stages(
            a,
            &self.plan,
            c,
            first,
            &mut self.k,
            &mut self.stage,
            &mut f,
            t,
            h,
            y,
        );
        let combine =
            |w: &[f64], j: usize| w.iter().enumerate().map(|(i, w)| w * self.k[i * n + j]).sum::<f64>();
        for (j, yj) in y.iter().enumerate() {
            self.candidate[j] = yj + h * combine(tab.b, j);
            match tab.error {
                ErrorEstimate::Single { e } => self.error[j] = h * combine(e, j),
                ErrorEstimate::Dop853 { e5, e3 } => {
                    self.error[j] = h * combine(e5, j);
                    self.error[n + j] = h * combine(e3, j);
                }
            }
        }
    }

    /// The scaled norm of the last error estimate, with weights atol + rtol max(|yᵢ|, |ŷᵢ|)
    /// (Hairer, Nørsett, Wanner (4.11)); ≤ 1 means acceptable.
    pub fn error_norm(&self, y: &[f64], rtol: f64, atol: f64) -> f64 {
        let n = y.len();
        let scaled_sum = |errors: &[f64]| -> f64 {
            y.iter()
                .zip(&self.candidate)
                .zip(errors)
                .map(|((a, b), e)| {
                    // An error of exactly zero meets any tolerance, even a zero one: without
                    // this, a component at rest with atol = 0 gives 0/0 = NaN, every step is
                    // rejected, and the run never ends. A non-zero error against a zero scale
                    // is infinite: rejected, as it must be.
                    if *e == 0.0 {
                        return 0.0;
                    }
                    let scale = atol + rtol * a.abs().max(b.abs());
                    (e / scale) * (e / scale)
                })
                .sum()
        };
        match self.tableau.error {
            ErrorEstimate::Single { .. } => (scaled_sum(&self.error[..n]) / n as f64).sqrt(),
            ErrorEstimate::Dop853 { .. } => {
                let (e5, e3) = (scaled_sum(&self.error[..n]), scaled_sum(&self.error[n..]));
                let denominator = e5 + 0.01 * e3;
                if denominator > 0.0 { e5 / (n as f64 * denominator).sqrt() } else { 0.0 }
            }
        }
    }

    /// Takes the candidate of the step from t of size h, which ends at `t_new`: `y` becomes
    /// it, f(t_new, y) becomes the next step's first stage, and with `dense` the step's dense
    /// output is prepared (DOP853 spends 3 more evaluations on it).
    pub fn accept<S: System + ?Sized>(
        &mut self,
        system: &S,
        t: f64,
        h: f64,
        t_new: f64,
        y: &mut [f64],
        dense: bool,
    ) {
        let tab = self.tableau;
        let n = y.len();
        let (r01, rest) = self.dense.split_at_mut(2 * n);
        if dense {
            let (r0, r1) = r01.split_at_mut(n);
            r0.copy_from_slice(y);
            for ((r1, c), y0) in r1.iter_mut().zip(&self.candidate).zip(&*y) {
                *r1 = c - y0;
            }
        }
        y.copy_from_slice(&self.candidate);
        let fresh = tab.new_point * n..(tab.new_point + 1) * n;
        if tab.new_point == tab.stages {
            system.rhs(t_new, y, &mut self.k[fresh.clone()]);
        }
        if dense {
            let (r0, r1) = r01.split_at(n);
            let mut f = |t: f64, y: &[f64], dydt: &mut [f64]| system.rhs(t, y, dydt);
            super::explicit_rk::explicit_stages(
                tab.a,
                &self.plan,
                tab.c,
                tab.new_point + 1,
                &mut self.k,
                &mut self.stage,
                &mut f,
                t,
                h,
                r0,
            );
            let (r23, high) = rest.split_at_mut(2 * n);
            let (r2, r3) = r23.split_at_mut(n);
            for j in 0..n {
                r2[j] = h * self.k[j] - r1[j];
                r3[j] = r1[j] - h * self.k[fresh.start + j] - r2[j];
            }
            for (d, r) in tab.dense.iter().zip(high.chunks_exact_mut(n)) {
                for (j, r) in r.iter_mut().enumerate() {
                    *r = h * d.iter().enumerate().map(|(i, d)| d * self.k[i * n + j]).sum::<f64>();
                }
            }
            self.dense_step = Some((t, h));
        } else {
            self.dense_step = None;
        }
        self.k.copy_within(fresh, 0);
        self.first_stage = Some(t_new);
    }

    /// The dense output of the last accepted step, if [`EmbeddedRk::accept`] prepared one.
    pub fn dense_output(&self) -> Option<DenseStep<'_>> {
        self.dense_step.map(|(t0, h)| DenseStep::new(t0, h, &self.dense))
    }
}

impl<S: System + ?Sized> Stepper<S> for EmbeddedRk {
    fn step(&mut self, system: &S, t: f64, h: f64, y: &mut [f64]) -> Result<(), Error> {
        // With a fixed step the FSAL stage is reused only if this step starts where the last
        // ended, which `first_stage` records.
        self.attempt(system, t, h, y);
        self.accept(system, t, h, t + h, y, false);
        Ok(())
    }
}

/// The stages (the first holds the next step's first-same-as-last derivative), the last
/// candidate and error estimate, the time that derivative belongs to, and the dense output.
impl Snapshot for EmbeddedRk {
    fn save(&self, out: &mut Words) {
        out.f64s(&self.k);
        out.f64s(&self.candidate);
        out.f64s(&self.error);
        out.opt_f64(self.first_stage);
        out.f64s(&self.dense);
        out.bool(self.dense_step.is_some());
        let (t0, h) = self.dense_step.unwrap_or((0.0, 0.0));
        out.f64(t0);
        out.f64(h);
    }
    fn restore(&mut self, from: &mut Reader<'_>) -> Result<(), Error> {
        from.f64s_into(&mut self.k)?;
        from.f64s_into(&mut self.candidate)?;
        from.f64s_into(&mut self.error)?;
        self.first_stage = from.opt_f64()?;
        from.f64s_into(&mut self.dense)?;
        let dense = from.bool()?;
        let (t0, h) = (from.f64()?, from.f64()?);
        self.dense_step = dense.then_some((t0, h));
        Ok(())
    }
}
