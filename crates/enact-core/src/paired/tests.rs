use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

fn side(task_correct: bool, pairwise_accuracy: f64) -> Side {
    Side {
        task_correct,
        pairwise_accuracy: Some(pairwise_accuracy),
    }
}

fn item(direction: Direction, states: usize, activity: &str, a: Side, b: Side) -> PairedItem {
    PairedItem {
        direction,
        step_length: StepLength::new(states).expect("3..=10"),
        activity: activity.to_owned(),
        a,
        b,
    }
}

#[test]
fn mcnemar_is_the_exact_binomial_tail_doubled() {
    // By hand: 8 against 2 of 10 discordant items, P(X <= 2) = (1 + 10 + 45) / 1024.
    assert_eq!(mcnemar_exact(8, 2), 112.0 / 1024.0);
    assert_eq!(mcnemar_exact(2, 8), 112.0 / 1024.0);
    assert_eq!(mcnemar_exact(12, 1), 14.0 / 4096.0);
    // No discordant item, or one: no evidence.
    assert_eq!(mcnemar_exact(0, 0), 1.0);
    assert_eq!(mcnemar_exact(1, 0), 1.0);
    assert_eq!(mcnemar_exact(5, 5), 1.0);
    // Many discordant items (over a thousand, 0.5^n underflows); the figures from exact
    // integer arithmetic (Python's math.comb and fractions).
    for (a, b, exact) in [
        (600, 500, 0.0028195449914364275),
        (3000, 2900, 0.1974390248435765),
        (700, 560, 8.869232897811355e-05),
    ] {
        let p = mcnemar_exact(a, b);
        assert!(
            (p - exact).abs() < 1e-9 * exact.max(1e-3),
            "{a} vs {b}: {p} not {exact}"
        );
    }
}

#[test]
fn cells_count_the_discordant_items_per_direction_and_step_length() {
    use Direction::{Forward, Inverse};
    let items = vec![
        item(Forward, 3, "cook", side(true, 1.0), side(false, 0.5)),
        item(Forward, 3, "cook", side(true, 1.0), side(true, 1.0)),
        item(Forward, 4, "wash", side(false, 0.0), side(true, 1.0)),
        item(Inverse, 3, "wash", side(false, 0.5), side(false, 0.0)),
        item(
            Inverse,
            3,
            "cook",
            Side {
                task_correct: false,
                pairwise_accuracy: None,
            },
            side(true, 1.0),
        ),
    ];
    let c = compare(&items, &PairedConfig::default()).expect("items");
    let o = &c.overall;
    assert_eq!((o.n, o.activities), (5, 2));
    assert_eq!((o.a_only, o.b_only, o.both, o.neither), (1, 2, 1, 1));
    assert_eq!((o.a_task_accuracy, o.b_task_accuracy), (0.4, 0.6));
    assert!((o.difference.estimate - -0.2).abs() < 1e-12);
    assert_eq!(o.mcnemar_p, 1.0);
    // Pairwise accuracy: each side over the items where it has one; the difference over the
    // items where both do (the fifth item has none for A).
    assert_eq!(o.a_pairwise_accuracy, Some(2.5 / 4.0));
    assert_eq!(o.b_pairwise_accuracy, Some(3.5 / 5.0));
    let pd = o.pairwise_difference.expect("four items with both");
    // 0.5 + 0 - 1 + 0.5 over four items.
    assert!(pd.estimate.abs() < 1e-12, "{pd:?}");

    let keys: Vec<(Option<Direction>, Option<u8>, usize)> = c
        .cells
        .iter()
        .map(|c| (c.direction, c.step_length.map(StepLength::get), c.n))
        .collect();
    assert_eq!(
        keys,
        [
            (Some(Forward), None, 3),
            (Some(Forward), Some(3), 2),
            (Some(Forward), Some(4), 1),
            (Some(Inverse), None, 2),
            (Some(Inverse), Some(3), 2),
        ]
    );
    let forward3 = &c.cells[1];
    assert_eq!((forward3.a_only, forward3.b_only, forward3.both), (1, 0, 1));
    assert_eq!(forward3.activities, 1);
    // Every figure is the same when computed again: the intervals are seeded.
    assert_eq!(compare(&items, &PairedConfig::default()), Some(c));
    assert_eq!(compare(&[], &PairedConfig::default()), None);
}

#[test]
fn activities_with_one_mean_give_a_point_interval_and_items_do_not() {
    // By hand: both activities' differences average 0.5, so every resample of whole activities
    // averages 0.5 too, however many of each it draws; resampled one by one, the items do not.
    let differences = [(0, 1.0), (0, 0.0), (1, 1.0), (1, 0.0), (1, 1.0), (1, 0.0)];
    let clustered = PairedConfig::default();
    let d = paired_difference(&differences, &clustered, 7).expect("items");
    assert_eq!((d.estimate, d.low, d.high), (0.5, 0.5, 0.5));
    let itemwise = PairedConfig {
        resampling: Resampling::Items,
        ..clustered
    };
    let d = paired_difference(&differences, &itemwise, 7).expect("items");
    assert_eq!(d.estimate, 0.5);
    assert!(d.low < 0.2 && d.high > 0.8, "{d:?}");
    assert_eq!(paired_difference(&[], &clustered, 7), None);
}

/// A standard normal draw (Box–Muller), for the simulation below.
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u: f64 = 1.0 - rng.random::<f64>();
    let v: f64 = rng.random();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

#[test]
fn with_correlated_activities_the_clustered_interval_covers_and_the_item_one_does_not() {
    // Seeded simulation: 20 activities of 15 items; an item's difference is its activity's
    // effect (shared by its items) plus its own noise, around a true difference of 0. The
    // clustered interval should cover 0 about 95 % of the time; the item interval, which
    // treats 300 correlated items as independent, is far too narrow.
    let mut rng = ChaCha8Rng::seed_from_u64(2024);
    let trials = 150;
    let config = |resampling| PairedConfig {
        resampling,
        resamples: 400,
        seed: 11,
        level: 0.95,
    };
    let (mut clustered, mut itemwise) = (0, 0);
    for trial in 0..trials {
        let mut differences = Vec::new();
        for activity in 0..20u32 {
            let effect = normal(&mut rng);
            for _ in 0..15 {
                differences.push((activity, effect + 0.5 * normal(&mut rng)));
            }
        }
        let covers = |d: Difference| d.low <= 0.0 && 0.0 <= d.high;
        let by_activity = paired_difference(&differences, &config(Resampling::Activities), trial);
        let by_item = paired_difference(&differences, &config(Resampling::Items), trial);
        clustered += usize::from(covers(by_activity.expect("items")));
        itemwise += usize::from(covers(by_item.expect("items")));
    }
    let rate = |covered: usize| covered as f64 / trials as f64;
    // A percentile bootstrap over 20 clusters covers a little under its level.
    assert!(
        (0.86..=0.99).contains(&rate(clustered)),
        "clustered coverage {}",
        rate(clustered)
    );
    assert!(rate(itemwise) < 0.6, "item coverage {}", rate(itemwise));
}

#[test]
fn resampling_reads_back_from_its_name() {
    for r in Resampling::ALL {
        assert_eq!(Resampling::parse(r.as_str()), Some(r));
    }
    assert_eq!(Resampling::parse("episodes"), None);
    assert_eq!(Resampling::default(), Resampling::Activities);
}
