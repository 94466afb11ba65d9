/* vulkan.c: the Vulkan backend (Vulkan 1.3: dynamic rendering, buffer
 * device addresses, scalar block layout). Runs unchanged on Mesa's
 * lavapipe (software) and on GPUs.
 *
 * No descriptor sets: the frame's constants live in a small host-visible
 * buffer per frame slot and the tile samples in VERTEX buffers; shaders
 * reach both through 64-bit device addresses passed as push constants,
 * next to the tile's origin, spacing and height scale.
 *
 * A frame is recorded at end_frame from what begin_frame, upload and
 * draw_tile collected: first the staged copies (a staging ring, one
 * region per frame slot, so an upload never waits for the device unless
 * its region is full), then sky, the filled tiles inside a
 * pipeline-statistics query (the GPU's own triangle count), the wireframe
 * overlay, and the readback (offscreen) or a blit to the swapchain
 * (window). Depth is reversed with an infinite far plane (see hw.h). */
#define _POSIX_C_SOURCE 200809L
#include "hw/hw_internal.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define GLFW_INCLUDE_NONE
#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <vulkan/vulkan.h>

static const uint32_t terrain_vert[] = {
#include "terrain.vert.inc"
};
static const uint32_t terrain_frag[] = {
#include "terrain.frag.inc"
};
static const uint32_t wire_frag[] = {
#include "wire.frag.inc"
};
static const uint32_t sky_vert[] = {
#include "sky.vert.inc"
};
static const uint32_t sky_frag[] = {
#include "sky.frag.inc"
};

#define MAX_SLOTS 2
#define RING_PER_SLOT ((uint64_t)32 << 20)

/* Must match Frame in shaders/common.glsl (scalar layout). */
typedef struct vk_frame_data {
    float view_proj[16];
    float inv_dir[16];
    float sun_fog[4];
    float ramp[4];
    float sky_zenith[4];
    float sky_horizon[4];
    uint32_t flags;
} vk_frame_data;

/* Must match Push in shaders/common.glsl. */
typedef struct vk_push {
    uint64_t frame, samples;
    float origin[2], spacing[2], limit[2];
    float z_base, z_step, morph;
    uint32_t n, bits, first;
    uint64_t tiles;   /* the frame's vk_tile_rec array */
    uint32_t draw_no; /* this draw's record in it */
} vk_push;

/* Must match TileRec in shaders/common.glsl (scalar layout, 80 bytes):
 * what a draw's neighbours need to read its samples. */
typedef struct vk_tile_rec {
    uint64_t samples;
    float origin[2], spacing[2];
    float z_base, z_step;
    uint32_t n, bits, first;
    uint32_t neighbour[8]; /* tsr_hw_tile_draw's */
    uint32_t pad;
} vk_tile_rec;

typedef struct vk_buffer {
    VkBuffer buf;
    VkDeviceMemory mem;
    VkDeviceAddress addr;
    uint64_t size;
    tsr_hw_buffer_kind kind; /* 0: free slot */
    void *mapped;
    uint64_t drawn_in; /* the last frame (frame_no) with a draw from it */
} vk_buffer;

typedef struct vk_copy {
    tsr_hw_buffer dst;
    uint64_t src_offset, dst_offset, size;
} vk_copy;

typedef struct vk_slot {
    VkCommandBuffer cb;
    VkFence fence;
    VkSemaphore acquired, rendered;
    vk_buffer frame; /* host-visible vk_frame_data */
    vk_buffer tiles; /* host-visible vk_tile_rec per draw; grows */
    bool submitted;
} vk_slot;

typedef struct vk_backend {
    tsr_hw_backend base; /* first: the table pointer is the object */
    tsr_allocator alloc;
    char name[VK_MAX_PHYSICAL_DEVICE_NAME_SIZE + 32];

    VkInstance inst;
    VkDebugUtilsMessengerEXT messenger;
    VkPhysicalDevice phys;
    VkPhysicalDeviceMemoryProperties mem_props;
    VkDevice dev;
    VkQueue queue;
    uint32_t qfam;
    VkCommandPool pool;
    bool has_stats, has_timestamps;
    double ts_period_ns;

    /* the offscreen target */
    VkImage color, depth;
    VkDeviceMemory color_mem, depth_mem;
    VkImageView color_view, depth_view;
    vk_buffer read_color, read_depth;
    bool readback_valid;

    VkPipelineLayout layout;
    VkPipeline fill, wire, sky;
    VkQueryPool stats_pool, ts_pool; /* per slot: 1 statistics, 2 timestamps */

    vk_buffer *bufs;
    uint32_t nbufs, capbufs;

    vk_buffer staging; /* MAX_SLOTS regions of RING_PER_SLOT bytes */
    uint64_t ring_head;
    vk_copy *copies;
    uint32_t ncopies, capcopies;

    vk_slot slots[MAX_SLOTS];
    uint32_t nslots, cur;
    bool in_frame;
    uint64_t frame_no; /* frames begun */
    bool lost;         /* a buffer this frame draws from was destroyed */
    tsr_hw_frame frame;
    tsr_hw_tile_draw *draws;
    uint32_t ndraws, capdraws;
    uint64_t frame_tris;
    tsr_hw_frame_stats last;

    /* window */
    GLFWwindow *window;
    VkSurfaceKHR surface;
    VkSwapchainKHR swapchain;
    VkImage *sc_images;
    uint32_t sc_count, sc_index;
    VkExtent2D sc_extent;
    VkFormat sc_format;
    bool vsync;
} vk_backend;

static const tsr_allocator *alloc_of(vk_backend *b) { return b->alloc.realloc ? &b->alloc : NULL; }

static const char *vk_result_str(VkResult r)
{
    switch (r) {
    case VK_SUCCESS: return "success";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "out of host memory";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "out of device memory";
    case VK_ERROR_INITIALIZATION_FAILED: return "initialization failed";
    case VK_ERROR_DEVICE_LOST: return "device lost";
    case VK_ERROR_LAYER_NOT_PRESENT: return "layer not present";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "extension not present";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "feature not present";
    case VK_ERROR_INCOMPATIBLE_DRIVER: return "incompatible driver (no Vulkan 1.3 driver installed?)";
    case VK_ERROR_SURFACE_LOST_KHR: return "surface lost";
    case VK_ERROR_OUT_OF_DATE_KHR: return "swapchain out of date";
    default: return "error";
    }
}

/* ---- validation messages ------------------------------------------------ */

static VKAPI_ATTR VkBool32 VKAPI_CALL debug_cb(VkDebugUtilsMessageSeverityFlagBitsEXT sev,
                                               VkDebugUtilsMessageTypeFlagsEXT type,
                                               const VkDebugUtilsMessengerCallbackDataEXT *data, void *user)
{
    (void)type;
    vk_backend *b = user;
    if (sev >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        b->base.stats.validation_messages++;
        fprintf(stderr, "tessera: vulkan validation: %s\n", data->pMessage ? data->pMessage : "(no message)");
    }
    return VK_FALSE;
}

static bool layer_available(const char *name)
{
    uint32_t n = 0;
    if (vkEnumerateInstanceLayerProperties(&n, NULL) != VK_SUCCESS || n == 0)
        return false;
    VkLayerProperties *p = calloc(n, sizeof *p);
    if (!p)
        return false;
    bool found = false;
    if (vkEnumerateInstanceLayerProperties(&n, p) == VK_SUCCESS)
        for (uint32_t i = 0; i < n && !found; i++)
            found = strcmp(p[i].layerName, name) == 0;
    free(p);
    return found;
}

/* ---- memory and buffers --------------------------------------------------- */

static int find_memory(vk_backend *b, uint32_t bits, VkMemoryPropertyFlags want)
{
    for (uint32_t i = 0; i < b->mem_props.memoryTypeCount; i++)
        if ((bits & (1u << i)) && (b->mem_props.memoryTypes[i].propertyFlags & want) == want)
            return (int)i;
    return -1;
}

static bool make_buffer(vk_backend *b, vk_buffer *out, uint64_t size, VkBufferUsageFlags usage, bool host)
{
    memset(out, 0, sizeof *out);
    VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
                             .size = size,
                             .usage = usage | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT,
                             .sharingMode = VK_SHARING_MODE_EXCLUSIVE};
    if (vkCreateBuffer(b->dev, &bi, NULL, &out->buf) != VK_SUCCESS)
        return false;
    VkMemoryRequirements req;
    vkGetBufferMemoryRequirements(b->dev, out->buf, &req);
    int type = -1;
    if (host)
        type = find_memory(b, req.memoryTypeBits,
                           VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
    else {
        type = find_memory(b, req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
        if (type < 0)
            type = find_memory(b, req.memoryTypeBits, 0);
    }
    VkMemoryAllocateFlagsInfo fi = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO,
                                    .flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT};
    VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
                               .pNext = &fi,
                               .allocationSize = req.size,
                               .memoryTypeIndex = (uint32_t)type};
    if (type < 0 || vkAllocateMemory(b->dev, &ai, NULL, &out->mem) != VK_SUCCESS) {
        vkDestroyBuffer(b->dev, out->buf, NULL);
        out->buf = VK_NULL_HANDLE;
        return false;
    }
    vkBindBufferMemory(b->dev, out->buf, out->mem, 0);
    if (host && vkMapMemory(b->dev, out->mem, 0, VK_WHOLE_SIZE, 0, &out->mapped) != VK_SUCCESS) {
        vkFreeMemory(b->dev, out->mem, NULL);
        vkDestroyBuffer(b->dev, out->buf, NULL);
        out->buf = VK_NULL_HANDLE;
        return false;
    }
    VkBufferDeviceAddressInfo dai = {.sType = VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO, .buffer = out->buf};
    out->addr = vkGetBufferDeviceAddress(b->dev, &dai);
    out->size = size;
    return true;
}

static void free_buffer(vk_backend *b, vk_buffer *v)
{
    if (!v->buf)
        return;
    if (v->mapped)
        vkUnmapMemory(b->dev, v->mem);
    vkDestroyBuffer(b->dev, v->buf, NULL);
    vkFreeMemory(b->dev, v->mem, NULL);
    memset(v, 0, sizeof *v);
}

static vk_buffer *lookup(vk_backend *b, tsr_hw_buffer id)
{
    if (id == 0 || id > b->nbufs || b->bufs[id - 1].kind == 0)
        return NULL;
    return &b->bufs[id - 1];
}

static tsr_hw_buffer vb_create(tsr_hw_backend *self, tsr_hw_buffer_kind kind, uint64_t size)
{
    vk_backend *b = (vk_backend *)self;
    if (size == 0 || kind < TSR_HW_VERTEX || kind > TSR_HW_STAGING)
        return 0;
    uint32_t slot = UINT32_MAX;
    for (uint32_t i = 0; i < b->nbufs; i++)
        if (b->bufs[i].kind == 0) {
            slot = i;
            break;
        }
    if (slot == UINT32_MAX) {
        if (b->nbufs == b->capbufs) {
            uint32_t cap = b->capbufs ? b->capbufs * 2 : 16;
            vk_buffer *nb = tsr_realloc(alloc_of(b), b->bufs, cap * sizeof *nb);
            if (!nb)
                return 0;
            b->bufs = nb;
            b->capbufs = cap;
        }
        slot = b->nbufs++;
        memset(&b->bufs[slot], 0, sizeof b->bufs[slot]);
    }
    VkBufferUsageFlags usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    bool host = false;
    if (kind == TSR_HW_VERTEX)
        usage |= VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    else if (kind == TSR_HW_INDEX)
        usage |= VK_BUFFER_USAGE_INDEX_BUFFER_BIT;
    else {
        usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
        host = true;
    }
    if (!make_buffer(b, &b->bufs[slot], size, usage, host))
        return 0;
    b->bufs[slot].kind = kind;
    self->stats.buffers_live++;
    self->stats.bytes_live += size;
    return slot + 1;
}

static void vb_destroy_buffer(tsr_hw_backend *self, tsr_hw_buffer id)
{
    vk_backend *b = (vk_backend *)self;
    vk_buffer *v = lookup(b, id);
    if (!v)
        return;
    if (b->in_frame && v->drawn_in == b->frame_no)
        b->lost = true; /* even if its id comes back before end_frame */
    /* a frame in flight may still read it */
    vkQueueWaitIdle(b->queue);
    self->stats.buffers_live--;
    self->stats.bytes_live -= v->size;
    free_buffer(b, v);
}

/* ---- one-shot commands and the staging ring -------------------------------- */

static VkCommandBuffer one_shot_begin(vk_backend *b)
{
    VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
                                      .commandPool = b->pool,
                                      .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                                      .commandBufferCount = 1};
    VkCommandBuffer cb;
    if (vkAllocateCommandBuffers(b->dev, &ai, &cb) != VK_SUCCESS)
        return VK_NULL_HANDLE;
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                   .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    vkBeginCommandBuffer(cb, &bi);
    return cb;
}

static bool one_shot_end(vk_backend *b, VkCommandBuffer cb)
{
    vkEndCommandBuffer(cb);
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO, .commandBufferCount = 1, .pCommandBuffers = &cb};
    bool ok = vkQueueSubmit(b->queue, 1, &si, VK_NULL_HANDLE) == VK_SUCCESS && vkQueueWaitIdle(b->queue) == VK_SUCCESS;
    vkFreeCommandBuffers(b->dev, b->pool, 1, &cb);
    return ok;
}

static void memory_barrier(VkCommandBuffer cb, VkPipelineStageFlags src, VkAccessFlags src_access,
                           VkPipelineStageFlags dst, VkAccessFlags dst_access)
{
    VkMemoryBarrier mb = {.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER, .srcAccessMask = src_access,
                          .dstAccessMask = dst_access};
    vkCmdPipelineBarrier(cb, src, dst, 0, 1, &mb, 0, NULL, 0, NULL);
}

/* Records the pending copies: after every earlier read of the
 * destinations (a write-after-read dependency on the vertex shaders of
 * earlier frames), and before any later shader read. */
static void record_copies(vk_backend *b, VkCommandBuffer cb)
{
    if (!b->ncopies)
        return;
    memory_barrier(cb, VK_PIPELINE_STAGE_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_VERTEX_INPUT_BIT, 0,
                   VK_PIPELINE_STAGE_TRANSFER_BIT, 0);
    for (uint32_t i = 0; i < b->ncopies; i++) {
        vk_buffer *d = lookup(b, b->copies[i].dst);
        if (!d)
            continue; /* destroyed after the upload: nothing to copy into */
        VkBufferCopy r = {.srcOffset = b->copies[i].src_offset, .dstOffset = b->copies[i].dst_offset,
                          .size = b->copies[i].size};
        vkCmdCopyBuffer(cb, b->staging.buf, d->buf, 1, &r);
    }
    memory_barrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                   VK_PIPELINE_STAGE_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_VERTEX_INPUT_BIT,
                   VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_INDEX_READ_BIT);
    b->ncopies = 0;
}

/* Submits the pending copies now and waits: the ring is full (a stall,
 * counted), or an upload outside a frame. */
static bool flush_copies(vk_backend *b)
{
    VkCommandBuffer cb = one_shot_begin(b);
    if (!cb)
        return false;
    record_copies(b, cb);
    return one_shot_end(b, cb);
}

static uint64_t ring_base(vk_backend *b) { return (uint64_t)b->cur * RING_PER_SLOT; }

static bool vb_upload(tsr_hw_backend *self, tsr_hw_buffer id, uint64_t offset, const void *data, uint64_t size)
{
    vk_backend *b = (vk_backend *)self;
    vk_buffer *v = lookup(b, id);
    if (!v || !data || offset > v->size || size > v->size - offset)
        return false;
    if (v->kind == TSR_HW_STAGING) {
        memcpy((char *)v->mapped + offset, data, size);
        self->stats.bytes_uploaded += size;
        return true;
    }
    if (!b->in_frame) /* outside a frame: nothing may be in flight on the ring */
        vkQueueWaitIdle(b->queue);
    const char *src = data;
    uint64_t done = 0;
    while (done < size) {
        uint64_t room = RING_PER_SLOT - b->ring_head;
        if (room < 4) {
            if (!flush_copies(b))
                return false;
            self->stats.upload_stalls += b->in_frame;
            b->ring_head = 0;
            continue;
        }
        uint64_t chunk = size - done < room ? size - done : room;
        if (b->ncopies == b->capcopies) {
            uint32_t cap = b->capcopies ? b->capcopies * 2 : 256;
            vk_copy *nc = tsr_realloc(alloc_of(b), b->copies, cap * sizeof *nc);
            if (!nc)
                return false;
            b->copies = nc;
            b->capcopies = cap;
        }
        uint64_t at = ring_base(b) + b->ring_head;
        memcpy((char *)b->staging.mapped + at, src + done, chunk);
        b->copies[b->ncopies++] = (vk_copy){id, at, offset + done, chunk};
        b->ring_head += (chunk + 3) & ~(uint64_t)3;
        done += chunk;
    }
    self->stats.bytes_uploaded += size;
    if (!b->in_frame) {
        bool ok = flush_copies(b);
        b->ring_head = 0;
        return ok;
    }
    return true;
}

/* ---- the render target --------------------------------------------------- */

static bool make_image(vk_backend *b, VkFormat fmt, VkImageUsageFlags usage, VkImageAspectFlags aspect, VkImage *img,
                       VkDeviceMemory *mem, VkImageView *view)
{
    VkImageCreateInfo ii = {.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO,
                            .imageType = VK_IMAGE_TYPE_2D,
                            .format = fmt,
                            .extent = {b->base.width, b->base.height, 1},
                            .mipLevels = 1,
                            .arrayLayers = 1,
                            .samples = VK_SAMPLE_COUNT_1_BIT,
                            .tiling = VK_IMAGE_TILING_OPTIMAL,
                            .usage = usage,
                            .initialLayout = VK_IMAGE_LAYOUT_UNDEFINED};
    if (vkCreateImage(b->dev, &ii, NULL, img) != VK_SUCCESS)
        return false;
    VkMemoryRequirements req;
    vkGetImageMemoryRequirements(b->dev, *img, &req);
    int type = find_memory(b, req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (type < 0)
        type = find_memory(b, req.memoryTypeBits, 0);
    VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
                               .allocationSize = req.size,
                               .memoryTypeIndex = (uint32_t)type};
    if (type < 0 || vkAllocateMemory(b->dev, &ai, NULL, mem) != VK_SUCCESS)
        return false;
    vkBindImageMemory(b->dev, *img, *mem, 0);
    VkImageViewCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO,
                                .image = *img,
                                .viewType = VK_IMAGE_VIEW_TYPE_2D,
                                .format = fmt,
                                .subresourceRange = {aspect, 0, 1, 0, 1}};
    return vkCreateImageView(b->dev, &vi, NULL, view) == VK_SUCCESS;
}

static void image_barrier(VkCommandBuffer cb, VkImage img, VkImageAspectFlags aspect, VkImageLayout from,
                          VkImageLayout to, VkPipelineStageFlags src, VkAccessFlags src_access,
                          VkPipelineStageFlags dst, VkAccessFlags dst_access)
{
    VkImageMemoryBarrier ib = {.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER,
                               .srcAccessMask = src_access,
                               .dstAccessMask = dst_access,
                               .oldLayout = from,
                               .newLayout = to,
                               .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                               .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                               .image = img,
                               .subresourceRange = {aspect, 0, 1, 0, 1}};
    vkCmdPipelineBarrier(cb, src, dst, 0, 0, NULL, 0, NULL, 1, &ib);
}

/* ---- pipelines ------------------------------------------------------------ */

static VkShaderModule shader(vk_backend *b, const uint32_t *code, size_t bytes)
{
    VkShaderModuleCreateInfo si = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO, .codeSize = bytes,
                                   .pCode = code};
    VkShaderModule m = VK_NULL_HANDLE;
    vkCreateShaderModule(b->dev, &si, NULL, &m);
    return m;
}

typedef enum { PIPE_FILL, PIPE_WIRE, PIPE_SKY } pipe_kind;

static VkPipeline make_pipeline(vk_backend *b, pipe_kind kind)
{
    VkShaderModule vs = kind == PIPE_SKY ? shader(b, sky_vert, sizeof sky_vert)
                                         : shader(b, terrain_vert, sizeof terrain_vert);
    VkShaderModule fs = kind == PIPE_SKY    ? shader(b, sky_frag, sizeof sky_frag)
                        : kind == PIPE_WIRE ? shader(b, wire_frag, sizeof wire_frag)
                                            : shader(b, terrain_frag, sizeof terrain_frag);
    VkPipeline p = VK_NULL_HANDLE;
    if (vs && fs) {
        VkPipelineShaderStageCreateInfo st[2] = {
            {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_VERTEX_BIT,
             .module = vs, .pName = "main"},
            {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, .stage = VK_SHADER_STAGE_FRAGMENT_BIT,
             .module = fs, .pName = "main"}};
        VkPipelineVertexInputStateCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
        VkPipelineInputAssemblyStateCreateInfo ia = {
            .sType = VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO,
            .topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST};
        VkPipelineViewportStateCreateInfo vp = {.sType = VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO,
                                                .viewportCount = 1, .scissorCount = 1};
        VkPipelineRasterizationStateCreateInfo rs = {
            .sType = VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO,
            .polygonMode = kind == PIPE_WIRE ? VK_POLYGON_MODE_LINE : VK_POLYGON_MODE_FILL,
            .cullMode = VK_CULL_MODE_NONE,
            .frontFace = VK_FRONT_FACE_CLOCKWISE,
            .depthBiasEnable = kind == PIPE_WIRE,
            .depthBiasConstantFactor = 1.0f,
            .depthBiasSlopeFactor = 1.0f,
            .lineWidth = 1.0f};
        VkPipelineMultisampleStateCreateInfo ms = {.sType = VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO,
                                                   .rasterizationSamples = VK_SAMPLE_COUNT_1_BIT};
        VkPipelineDepthStencilStateCreateInfo ds = {
            .sType = VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO,
            .depthTestEnable = kind != PIPE_SKY,
            .depthWriteEnable = kind == PIPE_FILL,
            .depthCompareOp = kind == PIPE_WIRE ? VK_COMPARE_OP_GREATER_OR_EQUAL : VK_COMPARE_OP_GREATER};
        VkPipelineColorBlendAttachmentState cba = {.colorWriteMask = 0xF};
        VkPipelineColorBlendStateCreateInfo cb = {.sType = VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO,
                                                  .attachmentCount = 1, .pAttachments = &cba};
        VkDynamicState dyn[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
        VkPipelineDynamicStateCreateInfo dy = {.sType = VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO,
                                               .dynamicStateCount = 2, .pDynamicStates = dyn};
        VkFormat cf = VK_FORMAT_R8G8B8A8_UNORM;
        VkPipelineRenderingCreateInfo ri = {.sType = VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO,
                                            .colorAttachmentCount = 1,
                                            .pColorAttachmentFormats = &cf,
                                            .depthAttachmentFormat = VK_FORMAT_D32_SFLOAT};
        VkGraphicsPipelineCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO,
                                           .pNext = &ri,
                                           .stageCount = 2,
                                           .pStages = st,
                                           .pVertexInputState = &vi,
                                           .pInputAssemblyState = &ia,
                                           .pViewportState = &vp,
                                           .pRasterizationState = &rs,
                                           .pMultisampleState = &ms,
                                           .pDepthStencilState = &ds,
                                           .pColorBlendState = &cb,
                                           .pDynamicState = &dy,
                                           .layout = b->layout};
        if (vkCreateGraphicsPipelines(b->dev, VK_NULL_HANDLE, 1, &pi, NULL, &p) != VK_SUCCESS)
            p = VK_NULL_HANDLE;
    }
    if (vs)
        vkDestroyShaderModule(b->dev, vs, NULL);
    if (fs)
        vkDestroyShaderModule(b->dev, fs, NULL);
    return p;
}

/* ---- swapchain ------------------------------------------------------------ */

static void destroy_swapchain(vk_backend *b)
{
    if (b->swapchain)
        vkDestroySwapchainKHR(b->dev, b->swapchain, NULL);
    b->swapchain = VK_NULL_HANDLE;
    tsr_free(alloc_of(b), b->sc_images);
    b->sc_images = NULL;
    b->sc_count = 0;
}

static bool make_swapchain(vk_backend *b)
{
    vkDeviceWaitIdle(b->dev);
    VkSurfaceCapabilitiesKHR caps;
    if (vkGetPhysicalDeviceSurfaceCapabilitiesKHR(b->phys, b->surface, &caps) != VK_SUCCESS)
        return false;
    if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT))
        return false;
    uint32_t nf = 0;
    vkGetPhysicalDeviceSurfaceFormatsKHR(b->phys, b->surface, &nf, NULL);
    VkSurfaceFormatKHR fmts[64];
    if (nf > 64)
        nf = 64;
    vkGetPhysicalDeviceSurfaceFormatsKHR(b->phys, b->surface, &nf, fmts);
    if (!nf)
        return false;
    VkSurfaceFormatKHR fmt = fmts[0];
    for (uint32_t i = 0; i < nf; i++)
        if (fmts[i].format == VK_FORMAT_B8G8R8A8_UNORM || fmts[i].format == VK_FORMAT_R8G8B8A8_UNORM) {
            fmt = fmts[i];
            break;
        }
    VkExtent2D ext = caps.currentExtent;
    if (ext.width == UINT32_MAX) {
        int w, h;
        glfwGetFramebufferSize(b->window, &w, &h);
        ext.width = (uint32_t)(w > 0 ? w : 1);
        ext.height = (uint32_t)(h > 0 ? h : 1);
    }
    if (ext.width == 0 || ext.height == 0)
        return false; /* minimised */
    uint32_t count = caps.minImageCount + 1;
    if (caps.maxImageCount && count > caps.maxImageCount)
        count = caps.maxImageCount;
    VkPresentModeKHR mode = VK_PRESENT_MODE_FIFO_KHR;
    if (!b->vsync) {
        uint32_t nm = 0;
        VkPresentModeKHR modes[16];
        vkGetPhysicalDeviceSurfacePresentModesKHR(b->phys, b->surface, &nm, NULL);
        if (nm > 16)
            nm = 16;
        vkGetPhysicalDeviceSurfacePresentModesKHR(b->phys, b->surface, &nm, modes);
        for (uint32_t i = 0; i < nm; i++)
            if (modes[i] == VK_PRESENT_MODE_MAILBOX_KHR || modes[i] == VK_PRESENT_MODE_IMMEDIATE_KHR)
                mode = modes[i];
    }
    VkSwapchainKHR old = b->swapchain;
    VkSwapchainCreateInfoKHR si = {.sType = VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR,
                                   .surface = b->surface,
                                   .minImageCount = count,
                                   .imageFormat = fmt.format,
                                   .imageColorSpace = fmt.colorSpace,
                                   .imageExtent = ext,
                                   .imageArrayLayers = 1,
                                   .imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                   .imageSharingMode = VK_SHARING_MODE_EXCLUSIVE,
                                   .preTransform = caps.currentTransform,
                                   .compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR,
                                   .presentMode = mode,
                                   .clipped = VK_TRUE,
                                   .oldSwapchain = old};
    VkSwapchainKHR sc;
    if (vkCreateSwapchainKHR(b->dev, &si, NULL, &sc) != VK_SUCCESS)
        return false;
    b->swapchain = old;
    destroy_swapchain(b);
    b->swapchain = sc;
    vkGetSwapchainImagesKHR(b->dev, sc, &b->sc_count, NULL);
    b->sc_images = tsr_alloc(alloc_of(b), b->sc_count * sizeof *b->sc_images);
    if (!b->sc_images)
        return false;
    vkGetSwapchainImagesKHR(b->dev, sc, &b->sc_count, b->sc_images);
    b->sc_extent = ext;
    b->sc_format = fmt.format;
    return true;
}

/* ---- frames --------------------------------------------------------------- */

/* The pipeline-statistics triangle count and the device time of the
 * finished frame that slot q recorded, into st (left as they are where
 * the device has no such queries). */
static void read_queries(vk_backend *b, uint32_t q, tsr_hw_frame_stats *st)
{
    if (b->has_stats) {
        uint64_t prims = 0;
        if (vkGetQueryPoolResults(b->dev, b->stats_pool, q, 1, sizeof prims, &prims, sizeof prims,
                                  VK_QUERY_RESULT_64_BIT) == VK_SUCCESS)
            st->triangles = prims;
    }
    if (b->has_timestamps) {
        uint64_t ts[2];
        if (vkGetQueryPoolResults(b->dev, b->ts_pool, 2 * q, 2, sizeof ts, ts, sizeof ts[0],
                                  VK_QUERY_RESULT_64_BIT) == VK_SUCCESS)
            st->gpu_ms = (double)(ts[1] - ts[0]) * b->ts_period_ns * 1e-6;
    }
}

static bool vb_begin_frame(tsr_hw_backend *self, const tsr_hw_frame *f)
{
    vk_backend *b = (vk_backend *)self;
    if (b->in_frame || !f)
        return false;
    vk_slot *s = &b->slots[b->cur];
    if (s->submitted) {
        /* a frame of a window's: finished now, its device time known */
        vkWaitForFences(b->dev, 1, &s->fence, VK_TRUE, UINT64_MAX);
        s->submitted = false;
        read_queries(b, b->cur, &b->last);
    }
    b->frame = *f;
    b->in_frame = true;
    b->frame_no++;
    b->lost = false;
    b->ndraws = 0;
    b->frame_tris = 0;
    b->ring_head = 0;
    b->readback_valid = false;
    return true;
}

static bool vb_draw_tile(tsr_hw_backend *self, const tsr_hw_tile_draw *d)
{
    vk_backend *b = (vk_backend *)self;
    if (!b->in_frame || !d)
        return false;
    vk_buffer *sb = lookup(b, d->samples), *ib = lookup(b, d->indices);
    if (!sb || !ib || sb->kind != TSR_HW_VERTEX || ib->kind != TSR_HW_INDEX || !tsr_hw_draw_fits(d, sb->size, ib->size))
        return false;
    if (b->ndraws == b->capdraws) {
        uint32_t cap = b->capdraws ? b->capdraws * 2 : 1024;
        tsr_hw_tile_draw *nd = tsr_realloc(alloc_of(b), b->draws, cap * sizeof *nd);
        if (!nd)
            return false;
        b->draws = nd;
        b->capdraws = cap;
    }
    b->draws[b->ndraws++] = *d;
    sb->drawn_in = ib->drawn_in = b->frame_no;
    self->stats.draws++;
    self->stats.triangles_drawn += d->index_count / 3;
    b->frame_tris += d->index_count / 3;
    return true;
}

/* Inverse of a 3x3 matrix given by rows r0, r1, r2; out column-major in
 * a 4x4 (the shader's mat3(inv_dir)). */
static void inverse3(const double r[3][3], float out[16])
{
    double c00 = r[1][1] * r[2][2] - r[1][2] * r[2][1];
    double c01 = r[1][2] * r[2][0] - r[1][0] * r[2][2];
    double c02 = r[1][0] * r[2][1] - r[1][1] * r[2][0];
    double det = r[0][0] * c00 + r[0][1] * c01 + r[0][2] * c02;
    double inv[3][3] = {{c00, r[0][2] * r[2][1] - r[0][1] * r[2][2], r[0][1] * r[1][2] - r[0][2] * r[1][1]},
                        {c01, r[0][0] * r[2][2] - r[0][2] * r[2][0], r[0][2] * r[1][0] - r[0][0] * r[1][2]},
                        {c02, r[0][1] * r[2][0] - r[0][0] * r[2][1], r[0][0] * r[1][1] - r[0][1] * r[1][0]}};
    memset(out, 0, 16 * sizeof *out);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            out[j * 4 + i] = (float)(det != 0 ? inv[i][j] / det : 0);
    out[15] = 1;
}

static void fill_frame_data(vk_backend *b, vk_frame_data *fd)
{
    const tsr_hw_frame *f = &b->frame;
    memset(fd, 0, sizeof *fd);
    memcpy(fd->view_proj, f->view_proj, sizeof fd->view_proj);
    /* rows 0, 1 and 3 of the view-projection map a direction to clip
     * (x, y, w); their inverse maps (ndc_x, ndc_y, 1) back to a direction */
    double r[3][3];
    for (int j = 0; j < 3; j++) {
        r[0][j] = f->view_proj[j * 4 + 0];
        r[1][j] = f->view_proj[j * 4 + 1];
        r[2][j] = f->view_proj[j * 4 + 3];
    }
    inverse3(r, fd->inv_dir);
    memcpy(fd->sun_fog, f->sun, sizeof f->sun);
    fd->sun_fog[3] = f->fog_distance;
    fd->ramp[0] = (float)(f->zmin - f->eye[2]);
    fd->ramp[1] = (float)(f->zmax - f->eye[2]);
    fd->ramp[2] = f->spacing_min;
    const float zenith[4] = {0.28f, 0.46f, 0.78f, 1}, horizon[4] = {0.72f, 0.80f, 0.88f, 1};
    memcpy(fd->sky_zenith, zenith, sizeof zenith);
    memcpy(fd->sky_horizon, horizon, sizeof horizon);
    fd->flags = f->flags;
}

static uint32_t draw_bits(const tsr_hw_tile_draw *d)
{
    return (d->format == TSR_HW_HEIGHT_U16 ? 1u : 0u) | (uint32_t)d->level << 8 | (uint32_t)(d->parity & 3) << 16;
}

/* The frame's tile records (vk_tile_rec per draw) into the slot's buffer,
 * grown as needed; false when a draw names a neighbour beyond the frame's
 * draws or itself, when a draw's buffer was destroyed since draw_tile, or
 * when out of memory. */
static bool fill_tile_records(vk_backend *b, vk_slot *s)
{
    if (b->lost)
        return false; /* a draw's buffer destroyed since draw_tile (its id may be back) */
    for (uint32_t i = 0; i < b->ndraws; i++)
        for (int k = 0; k < 8; k++)
            if (b->draws[i].neighbour[k] > b->ndraws || b->draws[i].neighbour[k] == i + 1)
                return false;
    uint64_t need = (uint64_t)(b->ndraws ? b->ndraws : 1) * sizeof(vk_tile_rec);
    if (s->tiles.size < need) {
        uint64_t size = s->tiles.size * 2 > need ? s->tiles.size * 2 : need;
        free_buffer(b, &s->tiles);
        if (!make_buffer(b, &s->tiles, size, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true))
            return false;
    }
    vk_tile_rec *rec = s->tiles.mapped;
    for (uint32_t i = 0; i < b->ndraws; i++) {
        const tsr_hw_tile_draw *d = &b->draws[i];
        vk_tile_rec t = {.samples = lookup(b, d->samples)->addr + d->samples_offset,
                         .origin = {d->origin[0], d->origin[1]},
                         .spacing = {d->spacing[0], d->spacing[1]},
                         .z_base = d->z_base,
                         .z_step = d->z_step,
                         .n = d->n,
                         .bits = draw_bits(d),
                         .first = d->first_sample};
        memcpy(t.neighbour, d->neighbour, sizeof t.neighbour);
        memcpy(rec + i, &t, sizeof t);
    }
    return true;
}

static void push_draw(vk_backend *b, VkCommandBuffer cb, const tsr_hw_tile_draw *d, VkDeviceAddress frame,
                      VkDeviceAddress tiles, uint32_t draw_no)
{
    vk_push pc = {.frame = frame,
                  .samples = lookup(b, d->samples)->addr + d->samples_offset,
                  .origin = {d->origin[0], d->origin[1]},
                  .spacing = {d->spacing[0], d->spacing[1]},
                  .limit = {d->limit[0], d->limit[1]},
                  .z_base = d->z_base,
                  .z_step = d->z_step,
                  .morph = d->morph,
                  .n = d->n,
                  .first = d->first_sample,
                  .bits = draw_bits(d),
                  .tiles = tiles,
                  .draw_no = draw_no};
    vkCmdPushConstants(cb, b->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof pc, &pc);
}

static void draw_list(vk_backend *b, VkCommandBuffer cb, VkDeviceAddress frame, VkDeviceAddress tiles)
{
    tsr_hw_buffer bound = 0;
    for (uint32_t i = 0; i < b->ndraws; i++) {
        const tsr_hw_tile_draw *d = &b->draws[i];
        if (d->indices != bound) {
            vkCmdBindIndexBuffer(cb, lookup(b, d->indices)->buf, 0, VK_INDEX_TYPE_UINT32);
            bound = d->indices;
        }
        push_draw(b, cb, d, frame, tiles, i);
        if (d->index_count)
            vkCmdDrawIndexed(cb, d->index_count, 1, d->first_index, 0, 0);
    }
}

static bool vb_end_frame(tsr_hw_backend *self, tsr_hw_frame_stats *out)
{
    vk_backend *b = (vk_backend *)self;
    if (!b->in_frame)
        return false;
    b->in_frame = false;
    vk_slot *s = &b->slots[b->cur];
    /* a draw naming a neighbour it cannot have, or no memory for the
     * records: none of the frame's draws (its uploads still happen) */
    bool drawn = fill_tile_records(b, s);
    if (!drawn) {
        b->ndraws = 0;
        b->frame_tris = 0;
    }
    vk_frame_data fd;
    fill_frame_data(b, &fd);
    memcpy(s->frame.mapped, &fd, sizeof fd);

    /* the window's image, when there is one */
    bool present = false;
    if (b->window) {
        if (!b->swapchain && !make_swapchain(b))
            goto offscreen_only;
        VkResult r = vkAcquireNextImageKHR(b->dev, b->swapchain, UINT64_MAX, s->acquired, VK_NULL_HANDLE,
                                           &b->sc_index);
        if (r == VK_ERROR_OUT_OF_DATE_KHR) {
            if (!make_swapchain(b))
                goto offscreen_only;
            r = vkAcquireNextImageKHR(b->dev, b->swapchain, UINT64_MAX, s->acquired, VK_NULL_HANDLE, &b->sc_index);
        }
        present = r == VK_SUCCESS || r == VK_SUBOPTIMAL_KHR;
    }
offscreen_only:;

    VkCommandBuffer cb = s->cb;
    vkResetCommandBuffer(cb, 0);
    VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                   .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    vkBeginCommandBuffer(cb, &bi);
    uint32_t q = b->cur;
    if (b->has_stats)
        vkCmdResetQueryPool(cb, b->stats_pool, q, 1);
    if (b->has_timestamps) {
        vkCmdResetQueryPool(cb, b->ts_pool, 2 * q, 2);
        vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, b->ts_pool, 2 * q);
    }
    record_copies(b, cb);
    image_barrier(cb, b->color, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                  VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                  VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, 0,
                  VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
    image_barrier(cb, b->depth, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                  VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                  VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT, 0,
                  VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                  VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT);
    VkRenderingAttachmentInfo ca = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
                                    .imageView = b->color_view,
                                    .imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                                    .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
                                    .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
                                    .clearValue = {.color = {{fd.sky_horizon[0], fd.sky_horizon[1], fd.sky_horizon[2], 1}}}};
    VkRenderingAttachmentInfo da = {.sType = VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO,
                                    .imageView = b->depth_view,
                                    .imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                                    .loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR,
                                    .storeOp = VK_ATTACHMENT_STORE_OP_STORE,
                                    .clearValue = {.depthStencil = {0.0f, 0}}};
    VkRenderingInfo ri = {.sType = VK_STRUCTURE_TYPE_RENDERING_INFO,
                          .renderArea = {{0, 0}, {self->width, self->height}},
                          .layerCount = 1,
                          .colorAttachmentCount = 1,
                          .pColorAttachments = &ca,
                          .pDepthAttachment = &da};
    vkCmdBeginRendering(cb, &ri);
    VkViewport vp = {0, 0, (float)self->width, (float)self->height, 0, 1};
    VkRect2D sc = {{0, 0}, {self->width, self->height}};
    vkCmdSetViewport(cb, 0, 1, &vp);
    vkCmdSetScissor(cb, 0, 1, &sc);
    vk_push spc = {.frame = s->frame.addr};
    vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, b->sky);
    vkCmdPushConstants(cb, b->layout, VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof spc, &spc);
    vkCmdDraw(cb, 3, 1, 0, 0);
    if (b->has_stats)
        vkCmdBeginQuery(cb, b->stats_pool, q, 0);
    vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, b->fill);
    draw_list(b, cb, s->frame.addr, s->tiles.addr);
    if (b->has_stats)
        vkCmdEndQuery(cb, b->stats_pool, q);
    if (b->frame.flags & TSR_HW_FRAME_WIREFRAME) {
        vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_GRAPHICS, b->wire);
        draw_list(b, cb, s->frame.addr, s->tiles.addr);
    }
    vkCmdEndRendering(cb);

    image_barrier(cb, b->color, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                  VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
                  VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_READ_BIT);
    if (present) {
        VkImage img = b->sc_images[b->sc_index];
        image_barrier(cb, img, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                      VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_PIPELINE_STAGE_TRANSFER_BIT, 0,
                      VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT);
        VkImageBlit blit = {.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
                            .srcOffsets = {{0, 0, 0}, {(int32_t)self->width, (int32_t)self->height, 1}},
                            .dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
                            .dstOffsets = {{0, 0, 0}, {(int32_t)b->sc_extent.width, (int32_t)b->sc_extent.height, 1}}};
        vkCmdBlitImage(cb, b->color, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, img, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                       &blit, VK_FILTER_LINEAR);
        image_barrier(cb, img, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                      VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0);
    } else if (!b->window) {
        image_barrier(cb, b->depth, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                      VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                      VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT,
                      VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_TRANSFER_READ_BIT);
        VkBufferImageCopy rc = {.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
                                .imageExtent = {self->width, self->height, 1}};
        vkCmdCopyImageToBuffer(cb, b->color, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, b->read_color.buf, 1, &rc);
        rc.imageSubresource.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT;
        vkCmdCopyImageToBuffer(cb, b->depth, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, b->read_depth.buf, 1, &rc);
        memory_barrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_HOST_BIT,
                       VK_ACCESS_HOST_READ_BIT);
    }
    if (b->has_timestamps)
        vkCmdWriteTimestamp(cb, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, b->ts_pool, 2 * q + 1);
    vkEndCommandBuffer(cb);

    VkPipelineStageFlags wait_stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
    VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
                       .waitSemaphoreCount = present ? 1 : 0,
                       .pWaitSemaphores = &s->acquired,
                       .pWaitDstStageMask = &wait_stage,
                       .commandBufferCount = 1,
                       .pCommandBuffers = &cb,
                       .signalSemaphoreCount = present ? 1 : 0,
                       .pSignalSemaphores = &s->rendered};
    vkResetFences(b->dev, 1, &s->fence);
    if (vkQueueSubmit(b->queue, 1, &si, s->fence) != VK_SUCCESS)
        return false;
    s->submitted = true;
    self->stats.frames++;

    double t0 = tsr_hw_now_ms();
    tsr_hw_frame_stats st = {.triangles = b->frame_tris};
    if (present) {
        VkPresentInfoKHR pi = {.sType = VK_STRUCTURE_TYPE_PRESENT_INFO_KHR,
                               .waitSemaphoreCount = 1,
                               .pWaitSemaphores = &s->rendered,
                               .swapchainCount = 1,
                               .pSwapchains = &b->swapchain,
                               .pImageIndices = &b->sc_index};
        VkResult r = vkQueuePresentKHR(b->queue, &pi);
        if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR)
            make_swapchain(b);
    }
    if (!b->window || b->nslots == 1) {
        /* offscreen: the image is wanted now */
        vkWaitForFences(b->dev, 1, &s->fence, VK_TRUE, UINT64_MAX);
        s->submitted = false;
        b->readback_valid = !b->window;
    }
    st.submit_wait_ms = tsr_hw_now_ms() - t0;
    if (!s->submitted) {
        read_queries(b, q, &st);
        b->last = st;
    } else {
        /* still in flight (a window's frames overlap): the device time of
         * the latest frame known to have finished */
        st.gpu_ms = b->last.gpu_ms;
    }
    b->cur = (b->cur + 1) % b->nslots;
    if (out)
        *out = st;
    return drawn;
}

static bool vb_read_color(tsr_hw_backend *self, uint8_t *rgba)
{
    vk_backend *b = (vk_backend *)self;
    if (!b->readback_valid || !rgba)
        return false;
    memcpy(rgba, b->read_color.mapped, (size_t)self->width * self->height * 4);
    return true;
}

static bool vb_read_depth(tsr_hw_backend *self, float *depth)
{
    vk_backend *b = (vk_backend *)self;
    if (!b->readback_valid || !depth)
        return false;
    memcpy(depth, b->read_depth.mapped, (size_t)self->width * self->height * 4);
    return true;
}

/* ---- lifetime ------------------------------------------------------------- */

static void vb_destroy(tsr_hw_backend *self)
{
    vk_backend *b = (vk_backend *)self;
    if (b->dev) {
        vkDeviceWaitIdle(b->dev);
        for (uint32_t i = 0; i < b->nbufs; i++)
            free_buffer(b, &b->bufs[i]);
        free_buffer(b, &b->staging);
        free_buffer(b, &b->read_color);
        free_buffer(b, &b->read_depth);
        for (uint32_t i = 0; i < MAX_SLOTS; i++) {
            vk_slot *s = &b->slots[i];
            free_buffer(b, &s->frame);
            free_buffer(b, &s->tiles);
            if (s->fence)
                vkDestroyFence(b->dev, s->fence, NULL);
            if (s->acquired)
                vkDestroySemaphore(b->dev, s->acquired, NULL);
            if (s->rendered)
                vkDestroySemaphore(b->dev, s->rendered, NULL);
        }
        if (b->stats_pool)
            vkDestroyQueryPool(b->dev, b->stats_pool, NULL);
        if (b->ts_pool)
            vkDestroyQueryPool(b->dev, b->ts_pool, NULL);
        if (b->fill)
            vkDestroyPipeline(b->dev, b->fill, NULL);
        if (b->wire)
            vkDestroyPipeline(b->dev, b->wire, NULL);
        if (b->sky)
            vkDestroyPipeline(b->dev, b->sky, NULL);
        if (b->layout)
            vkDestroyPipelineLayout(b->dev, b->layout, NULL);
        if (b->color_view)
            vkDestroyImageView(b->dev, b->color_view, NULL);
        if (b->depth_view)
            vkDestroyImageView(b->dev, b->depth_view, NULL);
        if (b->color)
            vkDestroyImage(b->dev, b->color, NULL);
        if (b->depth)
            vkDestroyImage(b->dev, b->depth, NULL);
        if (b->color_mem)
            vkFreeMemory(b->dev, b->color_mem, NULL);
        if (b->depth_mem)
            vkFreeMemory(b->dev, b->depth_mem, NULL);
        destroy_swapchain(b);
        if (b->pool)
            vkDestroyCommandPool(b->dev, b->pool, NULL);
        vkDestroyDevice(b->dev, NULL);
    }
    if (b->surface)
        vkDestroySurfaceKHR(b->inst, b->surface, NULL);
    if (b->messenger) {
        PFN_vkDestroyDebugUtilsMessengerEXT fn =
            (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(b->inst, "vkDestroyDebugUtilsMessengerEXT");
        if (fn)
            fn(b->inst, b->messenger, NULL);
    }
    if (b->inst)
        vkDestroyInstance(b->inst, NULL);
    tsr_allocator a = b->alloc;
    const tsr_allocator *ap = a.realloc ? &a : NULL;
    tsr_free(ap, b->bufs);
    tsr_free(ap, b->copies);
    tsr_free(ap, b->draws);
    tsr_free(ap, b);
}

static int type_rank(VkPhysicalDeviceType t)
{
    switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
    }
}

static bool contains_nocase(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    for (; *hay; hay++) {
        size_t i = 0;
        while (i < n && hay[i] && tolower((unsigned char)hay[i]) == tolower((unsigned char)needle[i]))
            i++;
        if (i == n)
            return true;
    }
    return n == 0;
}

/* Whether a device can run the renderer: Vulkan 1.3, a graphics queue
 * (presenting to the surface, if any), and the features the shaders use. */
static bool device_usable(vk_backend *b, VkPhysicalDevice pd, uint32_t *qfam, char *why, size_t whylen)
{
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pd, &p);
    if (p.apiVersion < VK_API_VERSION_1_3) {
        snprintf(why, whylen, "Vulkan %u.%u, 1.3 needed", VK_API_VERSION_MAJOR(p.apiVersion),
                 VK_API_VERSION_MINOR(p.apiVersion));
        return false;
    }
    VkPhysicalDeviceVulkan13Features f13 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceVulkan12Features f12 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES,
                                            .pNext = &f13};
    VkPhysicalDeviceFeatures2 f = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, .pNext = &f12};
    vkGetPhysicalDeviceFeatures2(pd, &f);
    if (!f13.dynamicRendering || !f12.bufferDeviceAddress || !f12.scalarBlockLayout || !f.features.fillModeNonSolid) {
        snprintf(why, whylen, "lacks dynamic rendering, buffer device address, scalar layout or line fill");
        return false;
    }
    uint32_t nq = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &nq, NULL);
    VkQueueFamilyProperties qp[32];
    if (nq > 32)
        nq = 32;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &nq, qp);
    for (uint32_t i = 0; i < nq; i++) {
        if (!(qp[i].queueFlags & VK_QUEUE_GRAPHICS_BIT))
            continue;
        VkBool32 pres = VK_TRUE;
        if (b->surface)
            vkGetPhysicalDeviceSurfaceSupportKHR(pd, i, b->surface, &pres);
        if (pres) {
            *qfam = i;
            return true;
        }
    }
    snprintf(why, whylen, "no graphics queue%s", b->surface ? " that presents to the window" : "");
    return false;
}

static tsr_status pick_device(vk_backend *b, const char *want, tsr_error *err)
{
    uint32_t n = 0;
    vkEnumeratePhysicalDevices(b->inst, &n, NULL);
    if (n == 0)
        return tsr_error_set(err, TSR_ERR_UNSUPPORTED,
                             "no Vulkan device found (install mesa-vulkan-drivers for the lavapipe software device)");
    VkPhysicalDevice devs[16];
    if (n > 16)
        n = 16;
    vkEnumeratePhysicalDevices(b->inst, &n, devs);
    int best = -1, best_rank = 99;
    uint32_t best_q = 0;
    char list[1024] = "", why[160];
    for (uint32_t i = 0; i < n; i++) {
        VkPhysicalDeviceProperties p;
        vkGetPhysicalDeviceProperties(devs[i], &p);
        size_t len = strlen(list);
        snprintf(list + len, sizeof list - len, "%s%u: %s", i ? "; " : "", i, p.deviceName);
        if (want && *want) {
            char *end;
            long idx = strtol(want, &end, 10);
            bool match = *end == 0 ? idx == (long)i : contains_nocase(p.deviceName, want);
            if (!match)
                continue;
            uint32_t q;
            if (!device_usable(b, devs[i], &q, why, sizeof why))
                return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "Vulkan device '%s' (asked for by '%s'): %s",
                                     p.deviceName, want, why);
            best = (int)i;
            best_q = q;
            break;
        }
        uint32_t q;
        int rank = type_rank(p.deviceType);
        if (rank < best_rank && device_usable(b, devs[i], &q, why, sizeof why)) {
            best = (int)i;
            best_rank = rank;
            best_q = q;
        }
    }
    if (best < 0) {
        if (want && *want)
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "no Vulkan device matches '%s' (devices: %s)", want, list);
        return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "no usable Vulkan device (devices: %s; last refusal: %s)", list,
                             why);
    }
    b->phys = devs[best];
    b->qfam = best_q;
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(b->phys, &p);
    snprintf(b->name, sizeof b->name, "%s", p.deviceName);
    b->ts_period_ns = p.limits.timestampPeriod;
    return TSR_OK;
}

tsr_status tsr_hw_vulkan_create(const tsr_hw_vulkan_options *opts, const tsr_allocator *alloc,
                                tsr_hw_backend **out, tsr_error *err)
{
    *out = NULL;
    tsr_hw_vulkan_options o = {0};
    if (opts)
        o = *opts;
    if (!o.width)
        o.width = 1280;
    if (!o.height)
        o.height = 720;
    if (o.width > 16384 || o.height > 16384)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "render target %ux%u is larger than 16384", o.width, o.height);
    vk_backend *b = tsr_alloc(alloc, sizeof *b);
    if (!b)
        return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory");
    memset(b, 0, sizeof *b);
    if (alloc)
        b->alloc = *alloc;
    b->base.width = o.width;
    b->base.height = o.height;
    b->base.create_buffer = vb_create;
    b->base.upload = vb_upload;
    b->base.destroy_buffer = vb_destroy_buffer;
    b->base.begin_frame = vb_begin_frame;
    b->base.draw_tile = vb_draw_tile;
    b->base.end_frame = vb_end_frame;
    b->base.read_color = vb_read_color;
    b->base.read_depth = vb_read_depth;
    b->base.destroy = vb_destroy;
    b->base.name = b->name;
    b->window = o.window;
    b->vsync = o.vsync;
    b->nslots = o.window ? 2 : 1;
    tsr_status st = TSR_OK;
    VkResult r;

    /* instance */
    int validation = o.validation;
    if (validation == 0) {
        const char *env = getenv("TESSERA_VK_VALIDATION");
#ifndef NDEBUG
        validation = env && strcmp(env, "0") == 0 ? -1 : layer_available("VK_LAYER_KHRONOS_validation") ? 1 : -1;
#else
        validation = env && strcmp(env, "1") == 0 ? 1 : -1;
#endif
    }
    const char *layers[1] = {"VK_LAYER_KHRONOS_validation"};
    if (validation > 0 && !layer_available(layers[0])) {
        st = tsr_error_set(err, TSR_ERR_UNSUPPORTED,
                           "Vulkan validation layers asked for but not installed (vulkan-validationlayers)");
        goto fail;
    }
    const char *exts[16];
    uint32_t next = 0;
    if (o.window) {
        uint32_t ng = 0;
        const char **g = glfwGetRequiredInstanceExtensions(&ng);
        for (uint32_t i = 0; g && i < ng && next < 14; i++)
            exts[next++] = g[i];
    }
    if (validation > 0)
        exts[next++] = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    VkApplicationInfo app = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
                             .pApplicationName = "tessera",
                             .pEngineName = "tessera",
                             .apiVersion = VK_API_VERSION_1_3};
    VkDebugUtilsMessengerCreateInfoEXT dci = {
        .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
        .messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
        .messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
        .pfnUserCallback = debug_cb,
        .pUserData = b};
    VkInstanceCreateInfo ici = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
                                .pNext = validation > 0 ? &dci : NULL,
                                .pApplicationInfo = &app,
                                .enabledLayerCount = validation > 0 ? 1 : 0,
                                .ppEnabledLayerNames = layers,
                                .enabledExtensionCount = next,
                                .ppEnabledExtensionNames = exts};
    r = vkCreateInstance(&ici, NULL, &b->inst);
    if (r != VK_SUCCESS) {
        b->inst = VK_NULL_HANDLE;
        st = tsr_error_set(err, TSR_ERR_UNSUPPORTED,
                           "cannot create a Vulkan instance: %s (is a Vulkan driver installed? mesa-vulkan-drivers "
                           "provides lavapipe)",
                           vk_result_str(r));
        goto fail;
    }
    if (validation > 0) {
        PFN_vkCreateDebugUtilsMessengerEXT fn =
            (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(b->inst, "vkCreateDebugUtilsMessengerEXT");
        if (fn)
            fn(b->inst, &dci, NULL, &b->messenger);
    }
    if (o.window && glfwCreateWindowSurface(b->inst, (GLFWwindow *)o.window, NULL, &b->surface) != VK_SUCCESS) {
        st = tsr_error_set(err, TSR_ERR_UNSUPPORTED, "cannot create a Vulkan surface for the window");
        goto fail;
    }

    /* device */
    const char *want = o.device ? o.device : getenv("TESSERA_VK_DEVICE");
    st = pick_device(b, want, err);
    if (st != TSR_OK)
        goto fail;
    vkGetPhysicalDeviceMemoryProperties(b->phys, &b->mem_props);
    VkPhysicalDeviceFeatures have;
    vkGetPhysicalDeviceFeatures(b->phys, &have);
    b->has_stats = have.pipelineStatisticsQuery;
    {
        uint32_t nq = 0;
        VkQueueFamilyProperties qp[32];
        vkGetPhysicalDeviceQueueFamilyProperties(b->phys, &nq, NULL);
        if (nq > 32)
            nq = 32;
        vkGetPhysicalDeviceQueueFamilyProperties(b->phys, &nq, qp);
        b->has_timestamps = qp[b->qfam].timestampValidBits > 0 && b->ts_period_ns > 0;
    }
    VkPhysicalDeviceVulkan13Features f13_have = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceFeatures2 f2_have = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, .pNext = &f13_have};
    vkGetPhysicalDeviceFeatures2(b->phys, &f2_have);
    float prio = 1;
    VkDeviceQueueCreateInfo qci = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO, .queueFamilyIndex = b->qfam,
                                   .queueCount = 1, .pQueuePriorities = &prio};
    VkPhysicalDeviceVulkan13Features f13 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES,
                                            .dynamicRendering = VK_TRUE,
                                            /* lets shaders drop interface variables they do not read */
                                            .maintenance4 = f13_have.maintenance4};
    VkPhysicalDeviceVulkan12Features f12 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES,
                                            .pNext = &f13,
                                            .bufferDeviceAddress = VK_TRUE,
                                            .scalarBlockLayout = VK_TRUE};
    VkPhysicalDeviceFeatures2 f2 = {.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, .pNext = &f12};
    f2.features.fillModeNonSolid = VK_TRUE;
    f2.features.pipelineStatisticsQuery = b->has_stats;
    f2.features.vertexPipelineStoresAndAtomics = VK_FALSE;
    const char *dext[1] = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
    VkDeviceCreateInfo dci2 = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
                               .pNext = &f2,
                               .queueCreateInfoCount = 1,
                               .pQueueCreateInfos = &qci,
                               .enabledExtensionCount = o.window ? 1 : 0,
                               .ppEnabledExtensionNames = dext};
    r = vkCreateDevice(b->phys, &dci2, NULL, &b->dev);
    if (r != VK_SUCCESS) {
        b->dev = VK_NULL_HANDLE;
        st = tsr_error_set(err, TSR_ERR_UNSUPPORTED, "cannot create the Vulkan device on %s: %s", b->name,
                           vk_result_str(r));
        goto fail;
    }
    vkGetDeviceQueue(b->dev, b->qfam, 0, &b->queue);
    VkCommandPoolCreateInfo pci = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
                                   .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
                                   .queueFamilyIndex = b->qfam};
    if (vkCreateCommandPool(b->dev, &pci, NULL, &b->pool) != VK_SUCCESS)
        goto fail_resources;

    /* target, readback, staging, slots */
    if (!make_image(b, VK_FORMAT_R8G8B8A8_UNORM,
                    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
                    &b->color, &b->color_mem, &b->color_view) ||
        !make_image(b, VK_FORMAT_D32_SFLOAT, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                    VK_IMAGE_ASPECT_DEPTH_BIT, &b->depth, &b->depth_mem, &b->depth_view))
        goto fail_resources;
    uint64_t pixels = (uint64_t)o.width * o.height;
    if (!make_buffer(b, &b->read_color, pixels * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true) ||
        !make_buffer(b, &b->read_depth, pixels * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true) ||
        !make_buffer(b, &b->staging, RING_PER_SLOT * b->nslots, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true))
        goto fail_resources;
    for (uint32_t i = 0; i < b->nslots; i++) {
        vk_slot *s = &b->slots[i];
        VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
                                          .commandPool = b->pool,
                                          .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                                          .commandBufferCount = 1};
        VkFenceCreateInfo fci = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        VkSemaphoreCreateInfo sci = {.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
        if (vkAllocateCommandBuffers(b->dev, &ai, &s->cb) != VK_SUCCESS ||
            vkCreateFence(b->dev, &fci, NULL, &s->fence) != VK_SUCCESS ||
            vkCreateSemaphore(b->dev, &sci, NULL, &s->acquired) != VK_SUCCESS ||
            vkCreateSemaphore(b->dev, &sci, NULL, &s->rendered) != VK_SUCCESS ||
            !make_buffer(b, &s->frame, sizeof(vk_frame_data), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true))
            goto fail_resources;
    }
    if (b->has_stats) {
        VkQueryPoolCreateInfo qi = {.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
                                    .queryType = VK_QUERY_TYPE_PIPELINE_STATISTICS,
                                    .queryCount = MAX_SLOTS,
                                    .pipelineStatistics = VK_QUERY_PIPELINE_STATISTIC_INPUT_ASSEMBLY_PRIMITIVES_BIT};
        if (vkCreateQueryPool(b->dev, &qi, NULL, &b->stats_pool) != VK_SUCCESS)
            b->has_stats = false;
    }
    if (b->has_timestamps) {
        VkQueryPoolCreateInfo qi = {.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
                                    .queryType = VK_QUERY_TYPE_TIMESTAMP,
                                    .queryCount = 2 * MAX_SLOTS};
        if (vkCreateQueryPool(b->dev, &qi, NULL, &b->ts_pool) != VK_SUCCESS)
            b->has_timestamps = false;
    }

    /* pipelines */
    VkPushConstantRange pr = {VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(vk_push)};
    VkPipelineLayoutCreateInfo lci = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
                                      .pushConstantRangeCount = 1, .pPushConstantRanges = &pr};
    if (vkCreatePipelineLayout(b->dev, &lci, NULL, &b->layout) != VK_SUCCESS)
        goto fail_resources;
    b->fill = make_pipeline(b, PIPE_FILL);
    b->wire = make_pipeline(b, PIPE_WIRE);
    b->sky = make_pipeline(b, PIPE_SKY);
    if (!b->fill || !b->wire || !b->sky)
        goto fail_resources;
    *out = &b->base;
    return TSR_OK;

fail_resources:
    st = tsr_error_set(err, TSR_ERR_NOMEM, "cannot create the Vulkan render target, buffers or pipelines on %s",
                       b->name);
fail:
    vb_destroy(&b->base);
    return st;
}
