/* The codels of apart.gen. `apart_grab_wait` is async: it tells the tests it began, then waits
 * until they release it (apart_test_release), as a codel waits for its driver; `Tune`
 * counts its runs meanwhile. `publish` checks what the grab left in the service's local
 * and the ids. */
#define _POSIX_C_SOURCE 200809L
#include <stdatomic.h>
#include <time.h>

#include "apart_c_types.h"

atomic_int apart_test_started = 0;
atomic_int apart_test_release = 0;
/* what apart_grab_publish saw: the local `got` and ids `frames` the grab wrote */
atomic_int apart_test_published = 0;

genom_event
apart_grab_start(int32_t *got, const genom_context self)
{
  (void)self;
  *got = 1;
  return apart_grab;
}

genom_event
apart_grab_wait(int32_t *got, int32_t *frames, const apart_image *image,
           const genom_context self)
{
  struct timespec nap = { 0, 100000 };
  atomic_store(&apart_test_started, 1);
  while (!atomic_load(&apart_test_release)) nanosleep(&nap, NULL);
  *got += 40;
  *frames = 2;
  *image->data(self) = 7;
  if (image->write(self)) return genom_fatal;
  return apart_publish;
}

genom_event
apart_grab_publish(int32_t got, int32_t frames, const genom_context self)
{
  (void)self;
  atomic_store(&apart_test_published, got * 100 + frames);
  return apart_ether;
}

genom_event
apart_tune(int32_t *tunes, const genom_context self)
{
  (void)self;
  (*tunes)++;
  return apart_pause_start;
}
