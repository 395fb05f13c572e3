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

/// SplitMix64: small, fast, and enough to spread choices.
#[derive(Clone, Debug)]
pub(crate) struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number below `n` (`n` at least 1).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

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
