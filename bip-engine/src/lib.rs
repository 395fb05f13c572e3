//! `bip-engine`: the runtime engine that runs codels and gates every codel transition on
//! the verified model. (Built in a later step; see ../shared/DESIGN.md.)
