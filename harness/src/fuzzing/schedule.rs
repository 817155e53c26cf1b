//! Which input a guided campaign mutates next ([`Pool`]): the seeds and
//! the inputs that reached something new, each with the coverage features
//! it reached on the reference model, drawn by how rare those features
//! are among all the executions so far, and how quick the input is on the
//! board.
//!
//! A fault hides where the inputs seldom go: a software reset while BUSY
//! (3-5-4), a Decelerating Stop before the ramp's last part (3-3-2), a
//! second finish status read (3-4-1). An input that reaches a cell few
//! executions reach is worth more of the board's time than one whose
//! every cell each input reaches, as libFuzzer's entropic schedule and
//! AFL's favoured inputs weigh them; among those, a quick one costs less
//! of the budget.

use crate::time::Duration;
use rand::rngs::StdRng;
use rand::Rng;
use std::collections::{BTreeSet, HashMap};

/// An input's board time that counts as much as its rarity: an input
/// twice this long is drawn a third as often as an instant one of the
/// same features.
const QUICK: Duration = Duration::from_millis(10);

/// One input of the pool.
#[derive(Debug, Clone)]
pub struct Entry {
    pub input: Vec<u8>,
    /// The board time it took.
    pub took: Duration,
    /// The features it reached (ids of [`Pool`]'s).
    features: Vec<u32>,
}

/// The inputs a guided campaign mutates, and how often each feature has
/// been reached.
#[derive(Debug, Default)]
pub struct Pool {
    ids: HashMap<String, u32>,
    /// Executions that reached each feature, by id.
    hits: Vec<u64>,
    entries: Vec<Entry>,
}

impl Pool {
    pub fn new() -> Pool {
        Pool::default()
    }

    /// Counts an execution that reached `features`; their ids.
    pub fn note(&mut self, features: &BTreeSet<String>) -> Vec<u32> {
        features
            .iter()
            .map(|f| {
                let next = self.hits.len() as u32;
                let id = *self.ids.entry(f.clone()).or_insert(next);
                if id == next {
                    self.hits.push(0);
                }
                self.hits[id as usize] += 1;
                id
            })
            .collect()
    }

    /// Keeps `input`, which took `took` and reached the features `ids`
    /// ([`Pool::note`]'s).
    pub fn keep(&mut self, input: Vec<u8>, took: Duration, ids: Vec<u32>) {
        self.entries.push(Entry {
            input,
            took,
            features: ids,
        });
    }

    pub fn len(&self) -> usize {
        self.entries.len()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn inputs(&self) -> impl Iterator<Item = &Vec<u8>> {
        self.entries.iter().map(|e| &e.input)
    }

    /// How much an entry is worth mutating: the rarity of its features
    /// (the sum of one over the executions that reached each), less for a
    /// slow input.
    fn weight(&self, e: &Entry) -> f64 {
        let rarity: f64 = e
            .features
            .iter()
            .map(|&id| 1.0 / self.hits[id as usize].max(1) as f64)
            .sum();
        let quick = QUICK.as_nanos() as f64;
        rarity * quick / (quick + e.took.as_nanos() as f64)
    }

    /// An entry drawn by its weight (the rarity of its features, less for a
    /// slow input); `None` from an empty pool.
    pub fn draw(&self, rng: &mut StdRng) -> Option<&Entry> {
        let weights: Vec<f64> = self.entries.iter().map(|e| self.weight(e)).collect();
        let total: f64 = weights.iter().sum();
        if self.entries.is_empty() {
            return None;
        }
        // Every weight is finite and positive (hits count from 1).
        if total.is_nan() || total <= 0.0 {
            return self.entries.get(rng.random_range(0..self.entries.len()));
        }
        let mut left = rng.random_range(0.0..total);
        for (e, w) in self.entries.iter().zip(&weights) {
            if left < *w {
                return Some(e);
            }
            left -= w;
        }
        self.entries.last()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn set(names: &[&str]) -> BTreeSet<String> {
        names.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn an_input_that_reached_a_rare_feature_is_drawn_more_often() {
        let mut p = Pool::new();
        let common = set(&["write init when idle"]);
        for _ in 0..50 {
            p.note(&common);
        }
        let ids = p.note(&common);
        p.keep(vec![1], Duration::from_millis(1), ids);
        let ids = p.note(&set(&["write init when idle", "software reset when busy"]));
        p.keep(vec![2], Duration::from_millis(1), ids);
        let mut rng = StdRng::seed_from_u64(1);
        let rare = (0..1000)
            .filter(|_| p.draw(&mut rng).expect("an entry").input == [2])
            .count();
        assert!(rare > 900, "the rare one drawn {rare} times in 1000");
    }

    #[test]
    fn of_two_inputs_with_the_same_features_the_quicker_is_drawn_more_often() {
        let mut p = Pool::new();
        let f = set(&["a", "b"]);
        let ids = p.note(&f);
        p.keep(vec![1], Duration::from_millis(90), ids.clone());
        p.keep(vec![2], Duration::ZERO, ids);
        let mut rng = StdRng::seed_from_u64(1);
        let quick = (0..1000)
            .filter(|_| p.draw(&mut rng).expect("an entry").input == [2])
            .count();
        assert!((850..=950).contains(&quick), "{quick} of 1000");
    }

    #[test]
    fn an_empty_pool_draws_nothing() {
        assert!(Pool::new().draw(&mut StdRng::seed_from_u64(1)).is_none());
    }
}
