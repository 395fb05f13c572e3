//! robots/rover.ron's generated bindings from the outside: the rover run through them,
//! random codels and requests through them under the step relation, and what must not
//! compile; and `models/typed.ron`'s, for the types the rover does not use.

mod alloc;
mod compile_fail;
mod property;
mod rover;
mod typed;
