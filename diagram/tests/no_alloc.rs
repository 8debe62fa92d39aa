//! The lookup must not allocate (ECU cycle rule). A counting global
//! allocator measures it; the count is per thread so the test harness's
//! own threads cannot disturb it.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell as StdCell;

use diagram::Query;

struct Counting;

thread_local! {
    static ALLOCATIONS: StdCell<usize> = const { StdCell::new(0) };
}

fn bump() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        bump();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        bump();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        bump();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn count() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

#[test]
fn ten_thousand_lookups_allocate_nothing() {
    let d = common::random_diagram(common::small_axes(), 3);
    let view = d.view();
    // Queries prepared up front: in range, out of range, NaN and infinities.
    let specials = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, -5.0, 1e9];
    let queries: Vec<Query> = (0..10_000)
        .map(|i| {
            let h = |f| common::hash01(i, f, 99);
            let mut q = Query {
                closing_speed_kph: 30.0 + 90.0 * h(0),
                opponent_mass_kg: 700.0 + 2400.0 * h(1),
                occupant_mass_kg: 25.0 + 110.0 * h(2),
                seat_distance_mm: 190.0 + 270.0 * h(3),
            };
            if i % 7 == 0 {
                q.occupant_mass_kg = specials[i % specials.len()];
            }
            q
        })
        .collect();
    // Sanity check that the counter works at all.
    let before_probe = count();
    let probe = vec![1u8; 16];
    assert!(count() > before_probe, "allocation counter does not count");
    drop(probe);

    let mut checksum = 0.0f32;
    let before = count();
    for q in &queries {
        let r = view.lookup(q);
        checksum += r.values.a_max_g + r.values.belt_limiter_kn;
    }
    let after = count();
    assert_eq!(
        after - before,
        0,
        "lookup allocated {} times",
        after - before
    );
    assert!(checksum.is_finite());
}
