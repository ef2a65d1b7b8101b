//! Unit checks of the building blocks: convex hull, Cholesky, the QP, the filter.

mod anatomy {
    use nalgebra::Vector2;
    use twinloop_ident::anatomy::{convex_hull, polygon_margin};

    #[test]
    fn hull_and_margin() {
        let pts: Vec<Vector2<f64>> = [
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (0.5, 0.5),
            (0.5, 0.0),
        ]
        .iter()
        .map(|&(x, y)| Vector2::new(x, y))
        .collect();
        let h = convex_hull(&pts);
        assert_eq!(h.len(), 4, "{h:?}");
        let poly: Vec<_> = h.iter().map(|&i| pts[i]).collect();
        assert!((polygon_margin(&poly, &Vector2::new(0.5, 0.5)) - 0.5).abs() < 1e-12);
        assert!((polygon_margin(&poly, &Vector2::new(0.9, 0.5)) - 0.1).abs() < 1e-12);
        assert!((polygon_margin(&poly, &Vector2::new(2.0, 0.5)) + 1.0).abs() < 1e-12);
    }
}

mod ik {
    use nalgebra::{DMatrix, DVector};
    use twinloop_gait::ik::cholesky_solve_in_place;

    #[test]
    fn cholesky_solves() {
        let m = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let x = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let mut b = &m * &x;
        let mut a = m.clone();
        assert!(cholesky_solve_in_place(&mut a, &mut b));
        assert!((b - x).amax() < 1e-14);
    }
}

mod qp {
    use nalgebra::{DMatrix, DVector};
    use twinloop_ident::qp::Qp;

    /// min (z0-3)^2 + (z1-3)^2 s.t. z0 + z1 = 2, z0 <= 0.5: optimum (0.5, 1.5).
    #[test]
    fn small_problem() {
        let h = DMatrix::identity(2, 2) * 2.0;
        let f = DVector::from_vec(vec![6.0, 6.0]);
        let eq = DMatrix::from_row_slice(1, 2, &[1.0, 1.0]);
        let eq_rhs = DVector::from_vec(vec![2.0]);
        let ineq = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, -1.0, 0.0]);
        let ineq_rhs = DVector::from_vec(vec![0.5, 10.0]);
        let qp = Qp {
            h: &h,
            f: &f,
            eq: &eq,
            eq_rhs: &eq_rhs,
            ineq: &ineq,
            ineq_rhs: &ineq_rhs,
        };
        let s = qp.solve(DVector::from_vec(vec![0.0, 2.0])).unwrap();
        assert!(
            (s.z[0] - 0.5).abs() < 1e-12 && (s.z[1] - 1.5).abs() < 1e-12,
            "{}",
            s.z
        );
        assert_eq!(s.active, vec![0]);
        // Multiplier: gradient of the objective along the bound.
        assert!(s.multipliers[0] > 0.0);
        // Without the bound active at the optimum: (1, 1).
        let ineq_rhs = DVector::from_vec(vec![5.0, 10.0]);
        let qp = Qp {
            ineq_rhs: &ineq_rhs,
            ..qp
        };
        let s = qp.solve(DVector::from_vec(vec![0.0, 2.0])).unwrap();
        assert!((s.z[0] - 1.0).abs() < 1e-12 && (s.z[1] - 1.0).abs() < 1e-12);
        assert!(s.active.is_empty());
    }
}

mod filter {
    use twinloop_ident::filter::butter_lowpass;

    #[test]
    fn unit_dc_gain_and_constant_passes() {
        for order in [1, 2, 3, 4, 6] {
            let f = butter_lowpass(order, 10.0, 150.0).unwrap();
            let dc: f64 = f.b.iter().sum::<f64>() / f.a.iter().sum::<f64>();
            assert!((dc - 1.0).abs() < 1e-12, "order {order}: {dc}");
            let y = f.filtfilt(&[3.5; 100]).unwrap();
            let e = y.iter().map(|v| (v - 3.5).abs()).fold(0.0, f64::max);
            assert!(e < 1e-10, "order {order}: {e}");
        }
        assert!(butter_lowpass(2, 80.0, 150.0).is_err());
        assert!(
            butter_lowpass(2, 10.0, 150.0)
                .unwrap()
                .filtfilt(&[1.0; 5])
                .is_err()
        );
    }
}
