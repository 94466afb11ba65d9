// Every public header compiles as C++ (../shared/STYLE.md item 10).
#include "hw/hw.h"
#include "patches/patches.h"
#include "patches/subd.h"
#include "terrain/terrain.h"
#include "tessellate/tessellate.h"

int main()
{
    tsr_mesh m;
    tsr_mesh_init(&m, TSR_MESH_NORMALS, nullptr);
    tsr_mesh_free(&m);
    tsr_load_options o = {};
    (void)o;
    return tsr_status_str(TSR_OK)[0] == 'o' ? 0 : 1;
}
