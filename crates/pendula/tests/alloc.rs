//! A step allocates nothing: every method on every catalogued system, counted by a global
//! allocator that tallies the current thread's allocations.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System as Heap};
use std::cell::Cell;

use pendula::integrator::embedded::EmbeddedRk;
use pendula::integrator::explicit_rk::ExplicitRk;
use pendula::integrator::gauss_legendre::Collocation;
use pendula::integrator::partitioned::PartitionedStepper;
use pendula::integrator::tao::TaoStepper;
use pendula::integrator::{METHODS, Requirement, Scheme, Stepper};
use pendula::observe::Ignore;
use pendula::system::double::DoublePendulum;
use pendula::system::oscillator::Oscillator;
use pendula::system::pendulum::Pendulum;
use pendula::system::{Hamiltonian, Model, Values};
use pendula::{End, RunSpec, Simulation};

use crate::support::values;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

struct Counting;

// SAFETY: forwards to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|a| a.set(a.get() + 1));
        // SAFETY: the caller upholds `alloc`'s contract.
        unsafe { Heap.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller upholds `dealloc`'s contract.
        unsafe { Heap.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|a| a.set(a.get() + 1));
        // SAFETY: the caller upholds `realloc`'s contract.
        unsafe { Heap.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static COUNTING: Counting = Counting;

fn allocations_during(f: impl FnOnce()) -> u64 {
    let before = ALLOCATIONS.with(Cell::get);
    f();
    ALLOCATIONS.with(Cell::get) - before
}

/// Runs 100 steps of every method on `model` (and its Hamiltonian form) after set-up,
/// counting allocations.
fn check<M: Model>(v: &Values) {
    let model = M::from_values(v);
    let spec = RunSpec { t0: 0.0, h: 1e-3, end: End::Steps(100) };
    for method in METHODS {
        let mut y = v.initial_state().to_vec();
        let count = match method.scheme {
            Scheme::ExplicitRk(t) => {
                let mut stepper = ExplicitRk::new(t, y.len());
                stepper.step(&model, 0.0, 1e-3, &mut y).unwrap();
                allocations_during(|| {
                    Simulation { system: &model, spec }.run(&mut stepper, &mut y, &mut Ignore).unwrap();
                })
            }
            Scheme::Embedded(t) => {
                let mut stepper = EmbeddedRk::new(t, y.len());
                stepper.step(&model, 0.0, 1e-3, &mut y).unwrap();
                allocations_during(|| {
                    Simulation { system: &model, spec }.run(&mut stepper, &mut y, &mut Ignore).unwrap();
                })
            }
            Scheme::Collocation(t) => {
                let form = model.hamiltonian_form().unwrap();
                let mut stepper = Collocation::new(t, y.len());
                stepper.step(&form, 0.0, 1e-3, &mut y).unwrap();
                allocations_during(|| {
                    Simulation { system: &form, spec }.run(&mut stepper, &mut y, &mut Ignore).unwrap();
                })
            }
            Scheme::Tao(scheme) => {
                let form = model.hamiltonian_form().unwrap();
                let mut stepper = TaoStepper::new(scheme, y.len() / 2);
                stepper.step(&form, 0.0, 1e-3, &mut y).unwrap();
                allocations_during(|| {
                    Simulation { system: &form, spec }.run(&mut stepper, &mut y, &mut Ignore).unwrap();
                })
            }
            Scheme::Partitioned(p) => {
                let form = model.hamiltonian_form().unwrap();
                if method.requirement == Requirement::Separable && !form.separable() {
                    continue;
                }
                let mut stepper = PartitionedStepper::new(p, y.len() / 2);
                stepper.step(&form, 0.0, 1e-3, &mut y).unwrap();
                allocations_during(|| {
                    Simulation { system: &form, spec }.run(&mut stepper, &mut y, &mut Ignore).unwrap();
                })
            }
        };
        assert_eq!(count, 0, "{} on {} allocated {count} times", method.name, M::INFO.name);
    }
}

#[test]
fn steps_allocate_nothing() {
    check::<Oscillator>(&values("oscillator", &[("drive_amplitude", 0.5), ("drive_frequency", 2.0)]));
    check::<Pendulum>(&values("pendulum", &[]));
    check::<DoublePendulum>(&values("double", &[]));
    check::<pendula::system::chain::Chain>(&values("chain", &[("links", 4.0)]));
}

/// The variational system of `lyapunov` (state and 4 tangent vectors, Jacobians by
/// num-dual) steps without allocating.
#[test]
fn tangent_steps_allocate_nothing() {
    let v = values("double", &[]);
    let model = v.build();
    let system = pendula::system::AsSystem(&*model);
    let tangent = pendula::analysis::Tangent { model: &system, n: 4, k: 4 };
    let Scheme::ExplicitRk(t) = pendula::integrator::explicit_rk::RK4.scheme else { unreachable!() };
    let mut stepper = ExplicitRk::new(t, 20);
    let mut y = vec![0.1; 20];
    y[..4].copy_from_slice(v.initial_state());
    stepper.step(&tangent, 0.0, 1e-3, &mut y).unwrap();
    let spec = RunSpec { t0: 0.0, h: 1e-3, end: End::Steps(100) };
    let count = allocations_during(|| {
        Simulation { system: &tangent, spec }.run(&mut stepper, &mut y, &mut Ignore).unwrap();
    });
    assert_eq!(count, 0, "the tangent system allocated {count} times");
}

/// The counter works: a step that allocates is seen.
#[test]
fn the_counter_sees_allocations() {
    assert!(allocations_during(|| drop(std::hint::black_box(vec![1.0_f64; 8]))) >= 1);
}
