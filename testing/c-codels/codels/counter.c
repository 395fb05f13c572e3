/* The codels of counter.gen, as a GenoM3 component's codels are written: they include
 * the headers bip codegen --c generates, nothing of bip's. What `step` returns is chosen
 * by the tests (counter_test_outcome), so that each declared outcome and each undeclared
 * one can be asked for. */
#include <stddef.h>

#include "accounter.h"
#include "counter_c_types.h"

/* What counter_count_step returns: 0 counts (pause::step until n, then ether), 1 throws
 * its declared e_limit (the event `raised` gives back), 2 throws e_stray (which Count does not declare), 3 returns `step`
 * (another codel's yield), 4 returns an event of no component, 5 returns genom_ok. */
int counter_test_outcome = 0;

static const char stray_event[] = "::counter::nowhere";

genom_event
counter_count_start(int32_t n, counter_ids *ids, const genom_context self)
{
  (void)self;
  ids->count = 0;
  ids->done = false;
  ids->gain = 0.25;
  return n > 0 ? counter_step : counter_ether;
}

genom_event
counter_count_step(int32_t n, counter_ids *ids, const genom_context self)
{
  counter_e_limit_detail limit;
  const counter_e_limit_detail *kept;
  genom_event raised = NULL;
  switch (counter_test_outcome) {
    case 1:
      /* throws, then asks the context what it kept: the same event and detail, or the
       * codel returns something undeclared */
      limit.at = ids->count;
      if (counter_e_limit(&limit, self) != counter_e_limit_id) return stray_event;
      kept = self->raised(&raised, self);
      return kept && kept->at == limit.at ? raised : stray_event;
    case 2: return counter_e_stray(self);
    case 3: return counter_step;
    case 4: return stray_event;
    case 5: return genom_ok;
    default: break;
  }
  ids->count++;
  ids->gain *= 2;
  if (ids->count < n) return counter_pause_step;
  ids->done = true;
  return counter_ether;
}

genom_event
counter_go(const place *to, place *at, const genom_context self)
{
  (void)self;
  *at = *to;
  return counter_ether;
}

genom_event
counter_idle_start(double gain, const genom_context self)
{
  (void)self;
  return gain >= 0 ? counter_ether : counter_e_stray(self);
}

/* SetGain's validation: a negative gain is refused with e_limit (its detail the gain,
 * truncated). */
genom_event
counter_set_gain_check(double g, const genom_context self)
{
  counter_e_limit_detail limit;
  if (g >= 0) return genom_ok;
  limit.at = (int32_t)g;
  return counter_e_limit(&limit, self);
}

/* SetGain: gives back the gain it replaces; above 100, e_limit and nothing changes;
 * exactly 42, an event of no component (which the engine takes as a fault). */
genom_event
counter_set_gain(double g, double *was, double *gain, const genom_context self)
{
  counter_e_limit_detail limit;
  if (g == 42) return stray_event;
  if (g > 100) {
    limit.at = (int32_t)g;
    return counter_e_limit(&limit, self);
  }
  *was = *gain;
  *gain = g;
  return genom_ok;
}

/* The ids' layout as gcc lays it out, for the tests to compare with the Rust mirror:
 * 0 the size, 1 the alignment, 2.. each member's offset. */
size_t
counter_ids_layout(int what)
{
  switch (what) {
    case 0: return sizeof(counter_ids);
    case 1: return _Alignof(counter_ids);
    case 2: return offsetof(counter_ids, count);
    case 3: return offsetof(counter_ids, done);
    case 4: return offsetof(counter_ids, gain);
    case 5: return offsetof(counter_ids, at);
    default: return (size_t)-1;
  }
}

/* Test hooks of bip_genom_c::LongDouble, no part of the component: long doubles as gcc
 * writes them, and whether one is exactly the double `want`. */
void counter_test_long_doubles(long double out[4]);
int counter_test_long_double_is(const long double *x, double want);

void
counter_test_long_doubles(long double out[4])
{
  out[0] = 1.0L;
  out[1] = -2.5L;
  out[2] = 1.0L / 3;
  out[3] = 1e300L;
}

int
counter_test_long_double_is(const long double *x, double want)
{
  return *x == (long double)want;
}
