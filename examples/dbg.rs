use glam::{DVec2, DVec3};
use sppm_lang::bezier::lathe::{Lathe, Solver};
fn main() {
    let cone = Lathe::new(&[vec![DVec2::new(1.0, 0.0), DVec2::new(0.0, 1.0)]], None).unwrap();
    println!(
        "{:?}",
        cone.intersect(
            DVec3::new(0.0, 5.0, 0.0),
            -DVec3::Y,
            0.0,
            1e9,
            Solver::Robust
        )
    );
    let p = Lathe::new(
        &[vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(0.5, 0.0),
            DVec2::new(1.0, 1.0),
        ]],
        None,
    )
    .unwrap();
    let o = DVec3::new(2.7864516916446433, 2.7965616323920885, -0.4855476273729957);
    let d = DVec3::new(-2.3297433827204768, -1.481368976737279, 0.40596482446110427);
    println!("{:?}", p.intersect(o, d, 1e-9, 1e9, Solver::Robust));
    println!(
        "{:?}",
        sppm_lang::bezier::reference::lathe(&p, o, d, 1e-9, 1e9)
    );
}
