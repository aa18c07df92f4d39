//! Cancellation: the `_cancellable` colour calls stop with
//! `Error::Cancelled` once their flag is set, also from another thread in
//! the middle of a long call, and the blocks they work in change no
//! colour.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

use std::thread;
use std::time::Duration;

use irid::cancel::Cancel;
use irid::color::gradient::colors_with_gradient_cancellable;
use irid::color::{stack_colors, stack_colors_cancellable, Sampling, SpectralIntegrator};
use irid::optics::{Layer, Material, Stack};
use irid::rough::rough_colors_cancellable;
use irid::Error;

/// A quarter-wave mirror of `pairs` pairs on glass: 9.3 µm at 60 pairs,
/// whose fringes are far narrower than the exact sampling's 1 nm, so every
/// angle is integrated again at finer steps.
fn mirror(pairs: usize) -> Stack {
    let pair = [
        Layer::new(Material::constant(1.45, 0.0), 95.0),
        Layer::new(Material::constant(2.3, 0.0), 60.0),
    ];
    Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: pair.iter().cycle().take(2 * pairs).cloned().collect(),
        substrate: Material::constant(1.52, 0.0),
    }
}

fn angles(n: usize) -> Vec<f64> {
    (0..n).map(|k| 89.0 * k as f64 / n as f64).collect()
}

/// A call given its flag: whether it stopped with `Error::Cancelled`.
type CancelledCall<'a> = dyn Fn(&Cancel) -> bool + Sync + 'a;

fn is_cancelled<T>(result: irid::Result<T>) -> bool {
    matches!(result, Err(Error::Cancelled))
}

#[test]
fn a_set_flag_stops_every_cancellable_colour_call() {
    let cancel = Cancel::new();
    cancel.set();
    let stack = mirror(3);
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let a = angles(5);
    assert!(is_cancelled(stack_colors_cancellable(
        &stack,
        &integrator,
        &a,
        &cancel
    )));
    assert!(is_cancelled(colors_with_gradient_cancellable(
        &stack,
        &integrator,
        &a,
        &cancel
    )));
    for roughness in [0.0, 0.3] {
        assert!(
            is_cancelled(rough_colors_cancellable(
                &stack,
                &integrator,
                &a,
                roughness,
                &cancel
            )),
            "roughness {roughness}"
        );
    }
    // Not set: the same calls run.
    let idle = Cancel::new();
    assert_eq!(
        stack_colors_cancellable(&stack, &integrator, &a, &idle)
            .unwrap()
            .len(),
        5
    );
}

#[test]
fn a_flag_set_from_another_thread_stops_a_long_call() {
    // Uncancelled, each call takes tens of seconds to minutes on one core:
    // the smooth colours of 300 angles each integrated again, and the
    // rough colour's sweep over the mirror's whole cos θ grid.
    let stack = mirror(60);
    let integrator = SpectralIntegrator::new(Sampling::Exact);
    let calls: [(&str, &CancelledCall<'_>); 3] = [
        ("smooth", &|c| {
            is_cancelled(stack_colors_cancellable(
                &stack,
                &integrator,
                &angles(300),
                c,
            ))
        }),
        ("gradient", &|c| {
            is_cancelled(colors_with_gradient_cancellable(
                &stack,
                &integrator,
                &angles(300),
                c,
            ))
        }),
        ("rough", &|c| {
            is_cancelled(rough_colors_cancellable(
                &stack,
                &integrator,
                &angles(10),
                0.3,
                c,
            ))
        }),
    ];
    for (name, call) in calls {
        let cancel = Cancel::new();
        let stopped = thread::scope(|s| {
            s.spawn(|| {
                thread::sleep(Duration::from_millis(200));
                cancel.set();
            });
            call(&cancel)
        });
        assert!(stopped, "{name}: ran to its end though cancelled");
    }
}

#[test]
fn the_blocks_of_the_smooth_colours_change_no_colour() {
    // 10 pairs: 101 angles a block; one layer: 742. Each angle alone
    // gives the same colour, bit for bit, as among all the others.
    let mut film = mirror(1);
    film.layers.truncate(1);
    for (stack, n) in [(mirror(10), 250), (film, 2000)] {
        let integrator = SpectralIntegrator::new(Sampling::Exact);
        let a = angles(n);
        let all = stack_colors(&stack, &integrator, &a).unwrap();
        for k in (0..n).step_by(n / 15) {
            let alone = stack_colors(&stack, &integrator, &a[k..=k]).unwrap();
            assert_eq!(
                alone[0],
                all[k],
                "{} layers, angle {}",
                stack.layers.len(),
                a[k]
            );
        }
    }
}
