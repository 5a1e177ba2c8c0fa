//! Times building the pre-integration tables at their default sizes:
//! `cargo run --release -p reference --example table_timing`.

use render_core::preintegration::{PsiTable, Table2d, Table3d};
use render_core::{Optics, TransferFunction};

fn main() {
    let optics = Optics {
        tf: TransferFunction::preset("low-opacity").unwrap(),
        scalar_min: 0.0,
        scalar_max: 1.0,
        length_unit: 1.0,
    };
    let n = Table3d::DEFAULT_SIZE;
    let t = std::time::Instant::now();
    let t3 = Table3d::build(&optics, n, n, 0.1);
    println!(
        "Table3d {n}³: {:.2} s, {} MiB",
        t.elapsed().as_secs_f64(),
        t3.bytes() >> 20
    );
    let t = std::time::Instant::now();
    let _ = Table2d::build(&optics, 512, 0.01);
    println!("Table2d 512²: {:.3} s", t.elapsed().as_secs_f64());
    let t = std::time::Instant::now();
    let _ = PsiTable::build(PsiTable::DEFAULT_SIZE);
    println!(
        "PsiTable {}²: {:.3} s",
        PsiTable::DEFAULT_SIZE,
        t.elapsed().as_secs_f64()
    );
    println!("threads: {}", rayon::current_num_threads());
}
