/* The null backend validates calls as a driver would and counts them. */
#include "check.h"
#include "hw/hw.h"

TEST(buffers_uploads_draws)
{
    tsr_hw_backend *b = tsr_hw_null_create(NULL);
    CHECK(b && strcmp(b->name, "null") == 0);
    tsr_hw_buffer vb = b->create_buffer(b, TSR_HW_VERTEX, 1024), ib = b->create_buffer(b, TSR_HW_INDEX, 600);
    CHECK(vb && ib && vb != ib);
    CHECK(b->create_buffer(b, TSR_HW_VERTEX, 0) == 0);
    CHECK(b->stats.buffers_live == 2 && b->stats.bytes_live == 1624);
    char data[1024] = {0};
    CHECK(b->upload(b, vb, 0, data, 1024));
    CHECK(!b->upload(b, vb, 1, data, 1024)); /* past the end */
    CHECK(!b->upload(b, 999, 0, data, 4));   /* no such buffer */
    CHECK(b->stats.bytes_uploaded == 1024);
    CHECK(b->draw(b, vb, ib, 150));
    CHECK(!b->draw(b, vb, ib, 151)); /* not whole triangles */
    CHECK(!b->draw(b, vb, ib, 153)); /* more indices than the buffer holds */
    CHECK(!b->draw(b, ib, vb, 3));   /* kinds swapped */
    CHECK(b->stats.draws == 1 && b->stats.triangles_drawn == 50);
    b->destroy_buffer(b, vb);
    CHECK(b->stats.buffers_live == 1 && b->stats.bytes_live == 600);
    CHECK(!b->upload(b, vb, 0, data, 4)); /* destroyed */
    tsr_hw_buffer again = b->create_buffer(b, TSR_HW_STAGING, 64);
    CHECK(again == vb); /* slot reused */
    b->destroy(b);
}

TEST_MAIN(T(buffers_uploads_draws))
