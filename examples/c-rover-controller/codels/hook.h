/* A test hook, no part of the components: with rover_hook_mode set (src/hooks.rs), each
 * codel returns an outcome the hook picks instead of its own. 0: the codel's own
 * outcome; 1: one of the outcomes it declares, at random; 2: as 1, or one time in five
 * an event it does not declare (counted in rover_hook_undeclared). */
#ifndef ROVER_HOOK_H
#define ROVER_HOOK_H

#include "genom3/c/event.h"

genom_event rover_hook(genom_event own, const genom_event *declared, int n);

#define ROVER_OUTCOME(own, ...)                                            \
  rover_hook((own), (const genom_event[]){__VA_ARGS__},                    \
             (int)(sizeof((const genom_event[]){__VA_ARGS__}) / sizeof(genom_event)))

#endif
