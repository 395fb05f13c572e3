//! How the engine chooses among steps the model allows at once.

/// The engine's choice among the enabled progress steps (codels of different activities
/// that the model leaves unordered, connectors of yours, internal transitions) and among
/// several steps of one interaction. The GenoM expansion orders codels, so with a GenoM
/// model there is rarely more than one (docs/engine.md, "Scheduling").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Policy {
    /// Always the first, in the model's order (interaction index, then step).
    First,
    /// In turn: the k-th choice takes candidate `k mod n`.
    #[default]
    RoundRobin,
    /// Uniformly at random from a seeded generator: deterministic for a seed.
    Seeded(u64),
}

pub(crate) use bip_model::Rng;

#[derive(Clone, Debug)]
pub(crate) struct Chooser {
    policy: Policy,
    turn: usize,
    rng: Rng,
}

impl Chooser {
    pub fn new(policy: Policy) -> Chooser {
        let seed = match policy {
            Policy::Seeded(s) => s,
            _ => 0,
        };
        Chooser {
            policy,
            turn: 0,
            rng: Rng::new(seed),
        }
    }

    /// One of `n` candidates (`n` at least 1).
    pub fn choose(&mut self, n: usize) -> usize {
        if n <= 1 {
            return 0;
        }
        match self.policy {
            Policy::First => 0,
            Policy::RoundRobin => {
                self.turn = self.turn.wrapping_add(1);
                self.turn % n
            }
            Policy::Seeded(_) => self.rng.below(n),
        }
    }
}
