/* traverse_instanced.h — ray traversal of the two-level BVH of an instanced scene
 * (include/idmr/instance_bvh_layout.h): closest hit and any hit.
 *
 * The top level is walked like a flat BVH (traverse.h's node test and child ordering); a
 * reference < 0 there is an instance, and the walk goes on in its prototype's BVH with the ray
 * moved into the instance's object space: origin' = W origin + w, direction' = W direction.
 * The direction is not renormalised, so t along the object-space ray is t along the world ray:
 * tmin, the current closest t and the stacked entry distances mean the same at both levels, and
 * a hit's t is the world-space t. The prototype's nodes and packets are tested by traverse.h's
 * own node and leaf tests (the watertight triangle test, the widened slab test), on the
 * object-space ray, so grazing rays and huge or tiny scales behave as in the flat traversal:
 * the transform is one more rounding of the ray (an ulp or so of the object-space origin and
 * direction), as in Embree's instancing.
 *
 * One stack serves both levels: entering an instance records the stack depth (instance_base);
 * when the walk pops back down to it, the prototype is done and the walk is back at the top
 * level, with the world ray. The top level leaves at most 3 * IDMR_BVH_MAX_DEPTH entries
 * pending below a prototype's walk, which needs the flat traversal's bound above them:
 * IDMR_INSTANCE_STACK_SIZE = 193 entries. Private memory per work-item: closest hit 193 *
 * (4 + 4) = 1544 bytes of stack (the flat traversal's 776 bytes, twice), plus two
 * traverse_ray records (world and object space, about 100 bytes each) and the hit; any hit
 * 193 * 4 = 772 bytes of stack plus the two rays. */
#ifndef IDMR_TRAVERSE_INSTANCED_H
#define IDMR_TRAVERSE_INSTANCED_H

#include "idmr/instance_bvh_layout.h"
#include "lib/traverse.h"

/* The ray of instance `inst` in its object space, set up for traversal. */
inline traverse_ray traverse_instance_ray(global const idmr_instance *inst, float3 origin,
                                          float3 direction)
{
    global const float *m = inst->world_to_object;
    float3 o = (float3)(m[0] * origin.x + m[1] * origin.y + m[2] * origin.z + m[3],
                        m[4] * origin.x + m[5] * origin.y + m[6] * origin.z + m[7],
                        m[8] * origin.x + m[9] * origin.y + m[10] * origin.z + m[11]);
    float3 d = (float3)(m[0] * direction.x + m[1] * direction.y + m[2] * direction.z,
                        m[4] * direction.x + m[5] * direction.y + m[6] * direction.z,
                        m[8] * direction.x + m[9] * direction.y + m[10] * direction.z);
    return traverse_setup(o, d);
}

/* Enters instance `inst`: its prototype's nodes and leaves into *level_nodes and
 * *prototype_leaves; returns the ray in its object space. */
inline traverse_ray traverse_enter_instance(global const idmr_instance *inst, float3 origin,
                                            float3 direction, global const idmr_bvh_node *nodes,
                                            global const idmr_triangle4 *leaves,
                                            global const idmr_bvh_node **level_nodes,
                                            global const idmr_triangle4 **prototype_leaves)
{
    *level_nodes = nodes + inst->node_offset;
    *prototype_leaves = leaves + inst->leaf_offset;
    return traverse_instance_ray(inst, origin, direction);
}

/* Closest hit along origin + t*direction, t in (tmin, tmax): t, u, v, the prototype's
 * triangle and the instance (both IDMR_NO_HIT when nothing is hit). */
inline idmr_instance_hit traverse_instanced_closest(global const idmr_bvh_node *top_nodes,
                                                    global const idmr_instance *instances,
                                                    global const idmr_bvh_node *nodes,
                                                    global const idmr_triangle4 *leaves,
                                                    float3 origin, float3 direction, float tmin,
                                                    float tmax)
{
    const traverse_ray world = traverse_setup(origin, direction);
    traverse_ray ray = world;
    idmr_hit hit = traverse_no_hit(tmax);
    unsigned int hit_instance = IDMR_NO_HIT;

    int stack_ref[IDMR_INSTANCE_STACK_SIZE];
    float stack_t[IDMR_INSTANCE_STACK_SIZE];
    int top = 0;
    int instance = -1; /* the instance being walked; -1 at the top level */
    int instance_base = 0;
    global const idmr_bvh_node *level_nodes = top_nodes;
    global const idmr_triangle4 *prototype_leaves = leaves;
    int ref = 0;
    for (;;) {
        if (ref >= 0) {
            global const idmr_bvh_node *node = level_nodes + ref;
            int mask;
            float4 t4 = traverse_node_boxes(&ray, node, tmin, hit.t, &mask);
            if (mask != 0) {
                ref = traverse_order_children(node, t4, mask, stack_ref, stack_t, &top);
                continue;
            }
        } else if (instance < 0) {
            instance = ~ref;
            ray = traverse_enter_instance(instances + instance, origin, direction, nodes, leaves,
                                          &level_nodes, &prototype_leaves);
            instance_base = top;
            ref = 0;
            continue;
        } else if (traverse_leaf(&ray, prototype_leaves, ref, tmin, &hit)) {
            hit_instance = (unsigned int)instance;
        }
        /* Pop the next reference that can still hold a closer hit, leaving the prototype when
         * its entries are all popped. */
        for (;;) {
            if (instance >= 0 && top == instance_base) {
                instance = -1;
                ray = world;
                level_nodes = top_nodes;
            }
            if (top == 0) {
                idmr_instance_hit out = {hit.t, hit.u, hit.v, hit.triangle, hit_instance, {0, 0, 0}};
                return out;
            }
            top--;
            if (stack_t[top] <= hit.t) {
                ref = stack_ref[top];
                break;
            }
        }
    }
}

/* True when anything lies along the ray within (tmin, tmax). */
inline bool traverse_instanced_any(global const idmr_bvh_node *top_nodes,
                                   global const idmr_instance *instances,
                                   global const idmr_bvh_node *nodes,
                                   global const idmr_triangle4 *leaves, float3 origin,
                                   float3 direction, float tmin, float tmax)
{
    const traverse_ray world = traverse_setup(origin, direction);
    traverse_ray ray = world;
    int stack_ref[IDMR_INSTANCE_STACK_SIZE];
    int top = 0;
    int instance = -1;
    int instance_base = 0;
    global const idmr_bvh_node *level_nodes = top_nodes;
    global const idmr_triangle4 *prototype_leaves = leaves;
    int ref = 0;
    for (;;) {
        if (ref >= 0) {
            global const idmr_bvh_node *node = level_nodes + ref;
            int mask;
            traverse_node_boxes(&ray, node, tmin, tmax, &mask);
            if (mask != 0) {
                ref = traverse_push_children(node, mask, stack_ref, &top);
                continue;
            }
        } else if (instance < 0) {
            instance = ~ref;
            ray = traverse_enter_instance(instances + instance, origin, direction, nodes, leaves,
                                          &level_nodes, &prototype_leaves);
            instance_base = top;
            ref = 0;
            continue;
        } else if (traverse_leaf_any(&ray, prototype_leaves, ref, tmin, tmax)) {
            return true;
        }
        if (instance >= 0 && top == instance_base) {
            instance = -1;
            ray = world;
            level_nodes = top_nodes;
        }
        if (top == 0)
            return false;
        ref = stack_ref[--top];
    }
}

#endif
