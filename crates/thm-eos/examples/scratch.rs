fn main() {
    for c in thm_eos::verification::cases() {
        let o = (c.run)().unwrap();
        for r in o.rows {
            println!(
                "{} | {} | {:.6e} | {:.6e} | {:.3e} | {} | {}",
                c.name, r.quantity, r.measured, r.reference, r.error, r.tolerance, r.pass
            );
        }
        for n in o.notes {
            println!("   note: {n}");
        }
    }
}
