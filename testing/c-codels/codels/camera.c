/* The codels of camera.gen, as a GenoM3 component's codels are written: its unbounded
 * sequences grown with genom_sequence_reserve, its strings malloc'ed and freed by the
 * codel that replaces them, as GenoM3's C mapping leaves them to the user. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accamera.h"
#include "camera_c_types.h"

/* `text` in a new buffer from malloc, in place of the string `*s` (freed). */
static int
replace(char **s, const char *text)
{
  char *fresh = malloc(strlen(text) + 1);
  if (!fresh) return -1;
  strcpy(fresh, text);
  free(*s);
  *s = fresh;
  return 0;
}

/* An image of width x height bytes (pixel k is (k + shots) mod 256) and its label on
 * port frame; the first row alone on port raw, its histogram on port hist; the label
 * kept in the ids. */
genom_event
camera_shoot(uint32_t width, uint32_t height, const char *label, camera_ids *ids,
             const camera_frame *frame, const camera_raw *raw,
             const camera_hist *hist, const genom_context self)
{
  sequence4_long *h = hist->data(self);
  cam_image *img = frame->data(self);
  sequence_octet *row = raw->data(self);
  uint32_t n = width * height, k;

  if (genom_sequence_reserve(&img->pixels, n)) return genom_fatal;
  for (k = 0; k < n; k++) img->pixels._buffer[k] = (uint8_t)(k + ids->shots);
  img->pixels._length = n;
  img->width = width;
  img->height = height;
  if (replace(&img->label, label)) return genom_fatal;

  if (genom_sequence_reserve(row, width)) return genom_fatal;
  memcpy(row->_buffer, img->pixels._buffer, width);
  row->_length = width;

  if (genom_sequence_reserve(&ids->labels, ids->labels._length + 1)) return genom_fatal;
  ids->labels._buffer[ids->labels._length] = NULL;
  if (replace(&ids->labels._buffer[ids->labels._length], label)) return genom_fatal;
  ids->labels._length++;
  ids->shots++;

  /* how many pixels in each quarter of 0..255 */
  for (k = 0; k < h->_maximum; k++) h->_buffer[k] = 0;
  for (k = 0; k < n; k++) h->_buffer[img->pixels._buffer[k] / 64]++;
  h->_length = h->_maximum;

  if (frame->write(self) || raw->write(self) || hist->write(self)) return genom_fatal;
  return camera_ether;
}

/* "label WxH sum S" of the image the request gives. */
genom_event
camera_describe(const cam_image *img, char **summary, const genom_context self)
{
  unsigned long sum = 0;
  uint32_t k;
  char text[128];
  (void)self;
  for (k = 0; k < img->pixels._length; k++) sum += img->pixels._buffer[k];
  snprintf(text, sizeof(text), "%s %ux%u sum %lu", img->label ? img->label : "(none)",
           (unsigned)img->width, (unsigned)img->height, sum);
  if (replace(summary, text)) return genom_fatal;
  return camera_ether;
}

/* The ids' title becomes `name`; the old one's bytes are the output. */
genom_event
camera_rename(const char *name, sequence_octet *old, char **title,
              const genom_context self)
{
  uint32_t n = *title ? (uint32_t)strlen(*title) : 0;
  (void)self;
  if (genom_sequence_reserve(old, n)) return genom_fatal;
  if (n) memcpy(old->_buffer, *title, n);
  old->_length = n;
  if (replace(title, name)) return genom_fatal;
  return camera_ether;
}

/* The mean of the image's pixels, and whether it is dark. */
genom_event
camera_stats(const cam_image *img, double *mean, char **verdict,
             const genom_context self)
{
  double sum = 0;
  uint32_t k;
  (void)self;
  for (k = 0; k < img->pixels._length; k++) sum += img->pixels._buffer[k];
  *mean = img->pixels._length ? sum / img->pixels._length : 0;
  if (replace(verdict, *mean < 64 ? "dark" : "lit")) return genom_fatal;
  return camera_ether;
}

/* How many images were shot. */
genom_event
camera_shots(uint32_t *n, const camera_ids *ids, const genom_context self)
{
  (void)self;
  *n = ids->shots;
  return camera_ether;
}

/* Reads port reference: a failed read is thrown as e_noref, with the errno of the
 * system error the read raised (-1 for another exception). */
genom_event
camera_compare(const camera_reference *reference, const genom_context self)
{
  genom_event ex = NULL;
  const genom_syserr_detail *d;
  camera_e_noref_detail noref;
  if (reference->read(self)) {
    d = self->raised(&ex, self);
    noref.code = ex == genom_syserr_id && d ? d->code : -1;
    return camera_e_noref(&noref, self);
  }
  return camera_ether;
}

/* The errno of the system error the last call raised (0 for none, -1 for another). */
static int32_t
syserr(genom_event e, const genom_context self)
{
  genom_event ex = NULL;
  const genom_syserr_detail *d;
  if (!e) return 0;
  d = self->raised(&ex, self);
  return ex == genom_syserr_id && d ? d->code : -1;
}

/* Instances of the multiple ports: levels' left and right opened and written (right
 * last closed), gains' instance a read from levels. Each step checked: the first that
 * fails is thrown as e_noref with its number (and the errno it raised in the tens). */
genom_event
camera_publish(double level, const camera_levels *levels, const camera_gains *gains,
               const genom_context self)
{
  camera_e_noref_detail step = { 0 };
  double *left, *right, *a;
  if (levels->open("left", self) || levels->open("right", self)) step.code = 1;
  else if (!(left = levels->data("left", self)) || !(right = levels->data("right", self)))
    step.code = 2;
  else if (levels->data("nowhere", self)) step.code = 3;
  else {
    *left = level;
    *right = -level;
    if (levels->write("right", self) || levels->write("left", self)) step.code = 4;
    else if (syserr(levels->write("nowhere", self), self) != ENOENT) step.code = 5;
    else if (levels->close("right", self)) step.code = 6;
    else if (syserr(levels->close("right", self), self) != ENOENT) step.code = 7;
    else if (levels->data("right", self)) step.code = 8;
    else if (gains->data("a", self)) step.code = 9;
    else if (gains->read("a", self)) step.code = 10 + syserr(gains->read("a", self), self) * 100;
    else if (!(a = gains->data("a", self)) || *a != level) step.code = 11;
    else if (syserr(levels->write(NULL, self), self) != EINVAL) step.code = 12;
  }
  return step.code ? camera_e_noref(&step, self) : camera_ether;
}

/* The sum of the counts the request gives. */
genom_event
camera_total(const sequence4_long *counts, int32_t *total, const genom_context self)
{
  uint32_t k;
  (void)self;
  *total = 0;
  for (k = 0; k < counts->_length; k++) *total += counts->_buffer[k];
  return camera_ether;
}
