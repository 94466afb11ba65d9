/* The null backend validates calls as a driver would and counts them:
 * each rule of hw.h has a check that a call breaking it fails and leaves
 * the counters alone. */
#include "check.h"
#include "hw/hw.h"

TEST(buffers_uploads)
{
    tsr_hw_backend *b = tsr_hw_null_create(640, 480, NULL);
    CHECK(b && strcmp(b->name, "null") == 0);
    CHECK(b->width == 640 && b->height == 480);
    tsr_hw_buffer vb = b->create_buffer(b, TSR_HW_VERTEX, 1024), ib = b->create_buffer(b, TSR_HW_INDEX, 600);
    CHECK(vb && ib && vb != ib);
    CHECK(b->create_buffer(b, TSR_HW_VERTEX, 0) == 0);            /* empty */
    CHECK(b->create_buffer(b, (tsr_hw_buffer_kind)7, 16) == 0);   /* no such kind */
    CHECK(b->stats.buffers_live == 2 && b->stats.bytes_live == 1624);
    char data[1024] = {0};
    CHECK(b->upload(b, vb, 0, data, 1024));
    CHECK(!b->upload(b, vb, 1, data, 1024)); /* past the end */
    CHECK(!b->upload(b, vb, 2048, data, 0)); /* offset past the end */
    CHECK(!b->upload(b, 999, 0, data, 4));   /* no such buffer */
    CHECK(!b->upload(b, 0, 0, data, 4));     /* 0 is never a buffer */
    CHECK(b->stats.bytes_uploaded == 1024);
    b->destroy_buffer(b, vb);
    CHECK(b->stats.buffers_live == 1 && b->stats.bytes_live == 600);
    CHECK(!b->upload(b, vb, 0, data, 4)); /* destroyed */
    tsr_hw_buffer again = b->create_buffer(b, TSR_HW_STAGING, 64);
    CHECK(again == vb); /* slot reused */
    uint8_t rgba[4];
    float depth[1];
    CHECK(!b->read_color(b, rgba) && !b->read_depth(b, depth)); /* no image */
    b->destroy(b);
}

/* A draw valid by every rule: a 4x4 tile, 25 samples. */
static tsr_hw_tile_draw valid_draw(tsr_hw_buffer vb, tsr_hw_buffer ib)
{
    tsr_hw_tile_draw d;
    memset(&d, 0, sizeof d);
    d.samples = vb;
    d.samples_offset = 0;
    d.format = TSR_HW_HEIGHT_F32;
    d.indices = ib;
    d.first_index = 0;
    d.index_count = 96; /* 32 triangles of a 4x4 tile */
    d.n = 4;
    d.spacing[0] = d.spacing[1] = 1;
    d.morph = 0.5f;
    return d;
}

TEST(frames_and_draws)
{
    tsr_hw_backend *b = tsr_hw_null_create(64, 64, NULL);
    /* 25 F32 samples = 100 bytes; 25 U16 samples = 13 words = 52 bytes */
    tsr_hw_buffer vb = b->create_buffer(b, TSR_HW_VERTEX, 200), ib = b->create_buffer(b, TSR_HW_INDEX, 4 * 150);
    tsr_hw_buffer sb = b->create_buffer(b, TSR_HW_STAGING, 200);
    tsr_hw_buffer big = b->create_buffer(b, TSR_HW_VERTEX, 4096), small = b->create_buffer(b, TSR_HW_VERTEX, 50);
    tsr_hw_frame frame;
    memset(&frame, 0, sizeof frame);
    tsr_hw_tile_draw d = valid_draw(vb, ib);

    CHECK(!b->draw_tile(b, &d));  /* outside a frame */
    CHECK(!b->end_frame(b, NULL)); /* no frame to end */
    CHECK(!b->begin_frame(b, NULL));
    CHECK(b->begin_frame(b, &frame));
    CHECK(!b->begin_frame(b, &frame)); /* begun twice */
    CHECK(b->draw_tile(b, &d));

    tsr_hw_tile_draw x;
#define BAD(field_change, why)                                                                     \
    do {                                                                                           \
        x = d;                                                                                     \
        field_change;                                                                              \
        CHECK_MSG(!b->draw_tile(b, &x), "%s", why);                                                \
    } while (0)
    BAD(x.samples = ib, "samples in an INDEX buffer");
    BAD(x.samples = sb, "samples in a STAGING buffer");
    BAD(x.samples = 0, "no samples buffer");
    BAD(x.samples = 99, "unknown samples buffer");
    BAD(x.indices = big, "indices in a VERTEX buffer (large enough)");
    BAD(x.indices = sb, "indices in a STAGING buffer");
    BAD(x.indices = 99, "unknown index buffer");
    BAD(x.samples_offset = 104, "F32 samples past the end: 104 + 100 > 200");
    BAD(x.samples_offset = 2, "offset not a multiple of 4");
    BAD(x.samples_offset = UINT64_MAX - 3, "offset overflowing");
    BAD(x.format = (tsr_hw_height_format)0, "no format");
    BAD(x.format = (tsr_hw_height_format)3, "unknown format");
    BAD((x.format = TSR_HW_HEIGHT_U16, x.samples_offset = 152), "U16 samples past the end: 152 + 52 > 200");
    BAD((x.format = TSR_HW_HEIGHT_U16, x.samples = small), "25 U16 samples take 13 words: 52 > 50 bytes");
    BAD(x.samples = small, "25 F32 samples: 100 > 50 bytes");
    BAD(x.first_sample = 1, "F32 samples do not start at a half word");
    BAD((x.format = TSR_HW_HEIGHT_U16, x.first_sample = 2), "first_sample beyond the first word");
    BAD((x.format = TSR_HW_HEIGHT_U16, x.first_sample = 1, x.samples_offset = 152),
        "U16 samples from a high half past the end: 152 + 52 > 200");
    BAD(x.index_count = 95, "not whole triangles");
    BAD((x.first_index = 57, x.index_count = 96), "indices past the end: 57 + 96 > 150");
    BAD((x.first_index = UINT32_MAX, x.index_count = 3), "first_index overflowing");
    BAD(x.n = 3, "odd n");
    BAD(x.n = 0, "n 0");
    BAD(x.n = TSR_TILE_MAX + 2, "n beyond TSR_TILE_MAX");
    BAD(x.spacing[0] = 0, "zero x spacing");
    BAD(x.spacing[1] = -1, "negative y spacing");
    BAD(x.spacing[0] = NAN, "NaN spacing");
    BAD(x.spacing[1] = INFINITY, "infinite spacing");
    BAD(x.origin[0] = NAN, "NaN origin");
    BAD(x.origin[1] = -INFINITY, "infinite origin");
    BAD(x.morph = -0.01f, "morph below 0");
    BAD(x.morph = 1.01f, "morph above 1");
    BAD(x.morph = NAN, "NaN morph");
#undef BAD
    CHECK(!b->draw_tile(b, NULL));

    /* the edges of the valid ranges are valid */
    x = d;
    x.samples_offset = 100; /* 100 + 100 == 200 */
    CHECK(b->draw_tile(b, &x));
    x = d;
    x.format = TSR_HW_HEIGHT_U16;
    x.samples_offset = 148; /* 148 + 52 == 200 */
    x.first_index = 54;     /* 54 + 96 == 150 */
    x.morph = 1;
    CHECK(b->draw_tile(b, &x));
    x.first_sample = 1; /* 25 halves after one: still 13 words */
    CHECK(b->draw_tile(b, &x));
    x.first_sample = 0;
    x.n = TSR_TILE_MIN;
    x.morph = 0;
    x.index_count = 0;
    CHECK(b->draw_tile(b, &x));

    tsr_hw_frame_stats fs;
    memset(&fs, 0xab, sizeof fs);
    CHECK(b->end_frame(b, &fs));
    CHECK(fs.triangles == 128 && fs.gpu_ms == 0 && fs.submit_wait_ms == 0);
    CHECK(b->stats.draws == 5 && b->stats.triangles_drawn == 128 && b->stats.frames == 1);

    CHECK(!b->draw_tile(b, &d)); /* the frame ended */
    CHECK(!b->end_frame(b, NULL));

    /* the next frame's triangles count from zero; stats may be NULL */
    CHECK(b->begin_frame(b, &frame));
    CHECK(b->draw_tile(b, &d));
    CHECK(b->end_frame(b, &fs));
    CHECK(fs.triangles == 32);
    CHECK(b->begin_frame(b, &frame));
    CHECK(b->end_frame(b, NULL));
    CHECK(b->stats.draws == 6 && b->stats.triangles_drawn == 160 && b->stats.frames == 3);

    /* neighbours name draws of the same frame, never itself: draw 1
     * naming draw 2 (number 3) is valid once draw 2 exists */
    CHECK(b->begin_frame(b, &frame));
    x = d;
    x.neighbour[0] = x.neighbour[1] = 1;
    x.neighbour[7] = 3;
    CHECK(b->draw_tile(b, &d) && b->draw_tile(b, &x) && b->draw_tile(b, &d));
    CHECK(b->end_frame(b, NULL));
    CHECK(b->stats.frames == 4);
    x.neighbour[7] = 2;
    CHECK(b->begin_frame(b, &frame));
    CHECK(b->draw_tile(b, &d) && b->draw_tile(b, &x)); /* names itself */
    CHECK(!b->end_frame(b, NULL));
    x.neighbour[7] = 0;
    x.neighbour[4] = 3;
    CHECK(b->begin_frame(b, &frame)); /* a failed end_frame still ends the frame */
    CHECK(b->draw_tile(b, &d) && b->draw_tile(b, &x)); /* names a third draw that never comes */
    memset(&fs, 0xab, sizeof fs);
    CHECK(!b->end_frame(b, &fs) && fs.triangles == 0);
    CHECK(b->stats.frames == 6 && b->stats.draws == 13); /* failed frames count */

    /* a buffer destroyed after a draw of the frame used it fails the frame */
    tsr_hw_buffer vb2 = b->create_buffer(b, TSR_HW_VERTEX, 200);
    x = d;
    x.samples = vb2;
    CHECK(b->begin_frame(b, &frame));
    CHECK(b->draw_tile(b, &x));
    b->destroy_buffer(b, vb2);
    CHECK(!b->end_frame(b, NULL));
    CHECK(b->begin_frame(b, &frame)); /* a buffer not drawn from may go */
    vb2 = b->create_buffer(b, TSR_HW_VERTEX, 200);
    CHECK(b->draw_tile(b, &d));
    b->destroy_buffer(b, vb2);
    CHECK(b->end_frame(b, NULL));
    CHECK(b->stats.draws == 15);

    /* a destroyed buffer cannot be drawn from */
    b->destroy_buffer(b, vb);
    CHECK(b->begin_frame(b, &frame));
    CHECK(!b->draw_tile(b, &d));
    CHECK(b->end_frame(b, NULL));
    CHECK(b->stats.draws == 15);
    b->destroy(b);
}

TEST_MAIN(T(buffers_uploads), T(frames_and_draws))
