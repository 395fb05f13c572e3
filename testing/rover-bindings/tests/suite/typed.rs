//! `models/typed.ron` run through its bindings: the model types the rover does not use
//! cross the typed contexts as the model declares them (ids of a range and a `Bool`
//! field, an `Int` port, a record with an `Int` field, an `Int`'s arguments and output),
//! and what the engine holds is what the codels gave; a function's codel and a
//! validation run at the request, typed alike. The run is a path of the model.

use crate::{assert_clean_path, end_of};
use bip_engine::{Bounded, Engine};
use bip_rover_bindings::typed::{self, arm, Joint};

/// The arm: `start` shifts the gear up and arms; `main` moves the joint to the requested
/// angle in steps of 30 degrees, publishing how far it is on `level` (0 to 100), and
/// gives the angle reached as the output.
#[derive(Default)]
struct Arm {
    /// What `main` saw on its ports and ids the last time it ran.
    seen: Vec<(Option<Bounded<0, 100>>, Option<Joint>, Bounded<-2, 3>, bool)>,
}

impl arm::Codels for Arm {
    fn move_start(&mut self, mut ctx: arm::MoveStartCtx<'_, '_>) -> arm::MoveStart {
        let up = Bounded::saturating(ctx.ids_gear().get() + 1);
        ctx.set_ids_gear(up);
        ctx.set_ids_armed(!ctx.ids_armed());
        arm::MoveStart::Main
    }

    fn move_main(&mut self, mut ctx: arm::MoveMainCtx<'_, '_>) -> arm::MoveMain {
        let goal = ctx.args().unwrap_or_default();
        self.seen.push((
            ctx.read_arm_level(),
            ctx.read_arm_joint().cloned(),
            ctx.ids_gear(),
            ctx.ids_armed(),
        ));
        let Some(joint) = ctx.port_joint_mut() else {
            return arm::MoveMain::EStuck;
        };
        let step = (goal.get() - joint.angle.get()).clamp(-30, 30);
        joint.angle = Bounded::saturating(joint.angle.get() + step);
        joint.ok = joint.angle == goal;
        let (angle, ok) = (joint.angle, joint.ok);
        // how far along, from 0 to 100
        let level = if goal.get() == 0 {
            100
        } else {
            100 * angle.get() / goal.get()
        };
        ctx.write_level(Bounded::saturating(level));
        ctx.set_output(angle);
        if ok {
            arm::MoveMain::Ether
        } else {
            arm::MoveMain::PauseMain
        }
    }

    /// Refuses a calibration to 0.
    fn calibrate_validate(
        &mut self,
        ctx: arm::CalibrateValidateCtx<'_, '_>,
    ) -> arm::CalibrateValidate {
        match ctx.args().map(|a| a.get()) {
            Some(0) => arm::CalibrateValidate::EZero,
            _ => arm::CalibrateValidate::Ether,
        }
    }

    /// Sets the gear to the argument less 2 and gives the gear it replaces; busy at 5.
    fn calibrate_start(&mut self, mut ctx: arm::CalibrateStartCtx<'_, '_>) -> arm::CalibrateStart {
        let a = ctx.args().map_or(0, |a| a.get());
        if a == 5 {
            return arm::CalibrateStart::EBusy;
        }
        let was = ctx.ids_gear();
        ctx.set_ids_gear(Bounded::saturating(a - 2));
        ctx.set_output(was);
        arm::CalibrateStart::Ether
    }
}

fn system() -> bip_engine::System {
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/models/typed.ron");
    bip_engine::load_file(model).unwrap_or_else(|e| panic!("{e:?}"))
}

#[test]
fn ints_and_bools_cross_the_typed_context_as_the_model_declares_them() {
    let system = system();
    let builder = Engine::builder(system.clone()).record(10_000);
    let mut engine = typed::bind(builder, Arm::default())
        .build()
        .expect("every codel is bound");
    let to_75 = arm::request_move(&mut engine, Bounded::of::<75>()).expect("queued");
    // 0, 30, 60, 75: the output is the angle reached, a Bounded of the output's range
    let end = end_of(&mut engine, 20, |t, r| to_75.end(t, r));
    assert_eq!(end, Some(arm::MoveEnd::Done(Some(Bounded::of::<75>()))));
    let inspect = engine.inspect();
    assert_eq!(inspect.ids("arm", "gear"), Some(1));
    assert_eq!(inspect.ids("arm", "armed"), Some(1));
    // the Int port holds an i64, the record its struct, whose Int field is a Bounded
    assert_eq!(inspect.port::<i64>("arm", "level"), Some(&100));
    assert_eq!(
        inspect.port::<Joint>("arm", "joint"),
        Some(&Joint {
            angle: Bounded::of::<75>(),
            ok: true
        })
    );

    // back to -15 (a level below 0 saturates to 0); start shifts up and disarms
    let to_minus_15 = arm::request_move(&mut engine, Bounded::of::<-15>()).expect("queued");
    let end = end_of(&mut engine, 20, |t, r| to_minus_15.end(t, r));
    assert_eq!(end, Some(arm::MoveEnd::Done(Some(Bounded::of::<-15>()))));
    assert_eq!(engine.inspect().ids("arm", "gear"), Some(2));
    assert_eq!(engine.inspect().ids("arm", "armed"), Some(0));
    assert_clean_path(&mut engine, &system);
}

#[test]
fn the_readers_give_what_the_writers_gave() {
    let system = system();
    let arm = std::sync::Arc::new(std::sync::Mutex::new(Arm::default()));
    /// The arm, shared with the test to read what it saw.
    struct Shared(std::sync::Arc<std::sync::Mutex<Arm>>);
    impl arm::Codels for Shared {
        fn move_start(&mut self, ctx: arm::MoveStartCtx<'_, '_>) -> arm::MoveStart {
            self.0.lock().expect("not poisoned").move_start(ctx)
        }
        fn move_main(&mut self, ctx: arm::MoveMainCtx<'_, '_>) -> arm::MoveMain {
            self.0.lock().expect("not poisoned").move_main(ctx)
        }
        fn calibrate_validate(
            &mut self,
            ctx: arm::CalibrateValidateCtx<'_, '_>,
        ) -> arm::CalibrateValidate {
            self.0.lock().expect("not poisoned").calibrate_validate(ctx)
        }
        fn calibrate_start(&mut self, ctx: arm::CalibrateStartCtx<'_, '_>) -> arm::CalibrateStart {
            self.0.lock().expect("not poisoned").calibrate_start(ctx)
        }
    }
    let mut engine = typed::bind(Engine::builder(system), Shared(arm.clone()))
        .build()
        .expect("every codel is bound");
    let ticket = arm::request_move(&mut engine, Bounded::of::<-60>()).expect("queued");
    let end = end_of(&mut engine, 20, |t, r| ticket.end(t, r));
    assert_eq!(end, Some(arm::MoveEnd::Done(Some(Bounded::of::<-60>()))));
    let seen = &arm.lock().expect("not poisoned").seen;
    let angle = |a: i64| Bounded::new(a).expect("in -90..=90");
    let level = |l: i64| Some(Bounded::new(l).expect("in 0..=100"));
    let joint = |a: i64, ok| {
        Some(Joint {
            angle: angle(a),
            ok,
        })
    };
    let (gear, armed) = (Bounded::of::<1>(), true);
    assert_eq!(
        seen,
        &[
            (None, None, gear, armed),
            (level(50), joint(-30, false), gear, armed),
        ],
        "the level and joint main wrote on its previous run, and the ids start wrote"
    );
}

#[test]
fn an_int_out_of_range_cannot_be_requested_and_the_engine_still_refuses_it_untyped() {
    // the typed request takes a Bounded: 91 cannot be made into an Int(-90, 90)
    assert_eq!(Bounded::<-90, 90>::new(91), None);
    let mut engine = typed::bind(Engine::builder(system()), Arm::default())
        .build()
        .expect("every codel is bound");
    let err = engine
        .request("arm", "Move", 91i64)
        .expect_err("out of Int(-90, 90)");
    assert!(err.to_string().contains("Int(-90, 90)"), "{err}");
}

#[test]
fn a_function_codel_and_a_validation_run_typed_at_the_request() {
    let system = system();
    let mut engine = typed::bind(Engine::builder(system.clone()).record(1000), Arm::default())
        .build()
        .expect("every codel is bound");
    // 4: the gear goes to 2, and the one it replaces (0) is the output
    let t = arm::request_calibrate(&mut engine, Bounded::of::<4>()).expect("queued");
    let end = end_of(&mut engine, 1, |tk, r| t.end(tk, r));
    assert_eq!(end, Some(arm::CalibrateEnd::Done(Some(Bounded::of::<0>()))));
    assert_eq!(engine.inspect().ids("arm", "gear"), Some(2));
    // 5: busy, the gear unchanged
    let t = arm::request_calibrate(&mut engine, Bounded::of::<5>()).expect("queued");
    let end = end_of(&mut engine, 1, |tk, r| t.end(tk, r));
    assert_eq!(
        end,
        Some(arm::CalibrateEnd::Exception(
            arm::CalibrateException::EBusy,
            None
        ))
    );
    assert_eq!(engine.inspect().ids("arm", "gear"), Some(2));
    // 0: refused by the validation, with its exception
    arm::request_calibrate(&mut engine, Bounded::of::<0>()).expect("queued");
    engine
        .run_until(bip_engine::Until::Quiescent)
        .expect("runs");
    let refused = engine.events().any(|ev| {
        matches!(ev, bip_engine::Event::Reply {
            reply: bip_engine::Reply::Refused(bip_engine::Refusal::Validation(bip_engine::Outcome::Exception(e))),
            ..
        } if &*e == "e_zero")
    });
    assert!(refused);
    assert_clean_path(&mut engine, &system);
}
