/* The mesh rule on a body's triangle contacts (edge and vertex contacts already represented
 * by a face or edge contact dropped), and the flat-mesh rule for logs. */
#include <math.h>

#include "world_internal.h"

/* Cylinder features from 3 up are the ends of a clipped support line (src/geom/cyl_tri.c). */
#define SD_CYL_LINE_PART 3

/* Global id of a triangle feature: kind in the low 2 bits (0 face, 1 edge, 2 vertex). */
static int64_t tri_feature_gid(const sd_walls *wl, int t, int f)
{
    int tf = f & ((1 << SD_TRI_FEATURE_BITS) - 1);
    int64_t part = (int64_t)(f >> SD_TRI_FEATURE_BITS) << 40;
    if (tf == SD_TRI_FACE) return part | ((int64_t)t << 2);
    if (tf < SD_TRI_VERT0) return part | ((int64_t)wl->edge_id[t][tf - SD_TRI_EDGE0] << 2) | 1;
    return part | ((int64_t)wl->vert_id[t][tf - SD_TRI_VERT0] << 2) | 2;
}

static int tri_has_edge(const sd_walls *wl, int t, int32_t e)
{
    return wl->edge_id[t][0] == e || wl->edge_id[t][1] == e || wl->edge_id[t][2] == e;
}

static int tri_has_vert(const sd_walls *wl, int t, int32_t v)
{
    return wl->vert_id[t][0] == v || wl->vert_id[t][1] == v || wl->vert_id[t][2] == v;
}

/* Flat-mesh rule for a log (cylinder–triangle pairs only). An edge of a flat floor shared by
 * two coplanar triangles (a seam), or a vertex shared by coplanar triangles, lies in the plane:
 * contacts of the log there are artefacts of the meshing (a cut of the log's support line, or
 * the seam under its side or end face, which would push the log along the floor). Contact X at
 * such a seam or vertex of triangle t is dropped when another contact Y of the same log is
 *  - a face contact on a triangle owning the feature (any part of the log);
 *  - a cut of the support line at the same seam while X is a cut too (both cuts go: the line's
 *    ends, rims or boundary edges, carry the log);
 *  - a cut of the support line on another triangle owning the feature while X is not a cut;
 *  - an edge/vertex contact (not a cut) listed earlier on another triangle owning the feature
 *    while X is not a cut (one of them is kept). */
static int is_line_cut(const sd_walls *wl, int t, int f, sd_vec3 n)
{
    int tf = f & ((1 << SD_TRI_FEATURE_BITS) - 1);
    return tf != SD_TRI_FACE && tf < SD_TRI_VERT0 && (f >> SD_TRI_FEATURE_BITS) >= SD_CYL_LINE_PART &&
           fabs(v3_dot(n, wl->tri[t].n)) > 1.0 - 1e-12;
}

/* Triangles t and u in one plane (to rounding). */
static int coplanar(const sd_walls *wl, int t, int u)
{
    const sd_tri *a = &wl->tri[t], *b = &wl->tri[u];
    if (fabs(v3_dot(a->n, b->n)) < 1.0 - 1e-12) return 0;
    for (int k = 0; k < 3; k++)
        if (fabs(v3_dot(v3_sub(b->v[k], a->v[0]), a->n)) > 1e-12 * (1.0 + v3_norm(v3_sub(b->v[k], a->v[0]))))
            return 0;
    return 1;
}

static int flat_mesh_drop(const sd_walls *wl, int t, int is_edge, int32_t id, int x_cut, int tq, int fo, sd_vec3 no,
                          int y_first)
{
    if (is_edge) {
        if (!wl->edge_flat[id] || !tri_has_edge(wl, tq, id)) return 0;
    } else {
        if (!tri_has_vert(wl, tq, id) || fabs(v3_dot(wl->tri[t].n, wl->tri[tq].n)) < 1.0 - 1e-12) return 0;
    }
    int tfo = fo & ((1 << SD_TRI_FEATURE_BITS) - 1);
    if (tfo == SD_TRI_FACE) return 1;
    int y_cut = is_line_cut(wl, tq, fo, no);
    if (x_cut) return y_cut && is_edge && wl->edge_id[tq][tfo - SD_TRI_EDGE0] == id;
    if (tq == t) return 0;
    return y_cut || y_first;
}

/* Mesh rule: an edge contact is dropped when the same body part has a face contact on a
 * triangle owning that edge, or the same edge was already taken; a vertex contact when a face
 * or edge contact touches that vertex, or the vertex was already taken. A sphere rolling across
 * a shared edge of a flat mesh thus always feels exactly one contact. */
void sd_contact_mesh_dedup(const sd_walls *wl, const sd_pair *pairs, sd_manifold *man, int from, int to)
{
    for (int p = from; p < to; p++) {
        sd_manifold *m = &man[p];
        for (int k = 0; k < m->n; k++) {
            int f = m->feature[k];
            int tf = f & ((1 << SD_TRI_FEATURE_BITS) - 1);
            if (tf == SD_TRI_FACE) continue;
            int part = f >> SD_TRI_FEATURE_BITS;
            int t = pairs[p].b;
            int64_t gid = tri_feature_gid(wl, t, f);
            int is_edge = tf < SD_TRI_VERT0;
            int32_t id = is_edge ? wl->edge_id[t][tf - SD_TRI_EDGE0] : wl->vert_id[t][tf - SD_TRI_VERT0];
            int drop = 0;
            if (pairs[p].kind == SD_PAIR_CT) {
                int x_cut = is_line_cut(wl, t, f, m->normal[k]);
                /* a log on a floor of triangles: its face contacts on the triangles under it
                 * carry it, and a seam of the floor under it, or an edge or vertex under its
                 * end face (normal along the floor's), is no contact of its own (near a face's
                 * rim a seam's deepest point can be nearer the side, normal sideways) */
                if (!x_cut &&
                    (fabs(v3_dot(m->normal[k], wl->tri[t].n)) > 1.0 - 1e-12 || (is_edge && wl->edge_flat[id])))
                    for (int q = from; q < to && !drop; q++)
                        for (int kk = 0; kk < man[q].n && !drop; kk++)
                            drop = (man[q].feature[kk] & ((1 << SD_TRI_FEATURE_BITS) - 1)) == SD_TRI_FACE &&
                                   coplanar(wl, t, pairs[q].b);
                for (int q = from; q < to && !drop; q++)
                    for (int kk = 0; kk < man[q].n && !drop; kk++)
                        if (!(q == p && kk == k))
                            drop = flat_mesh_drop(wl, t, is_edge, id, x_cut, pairs[q].b, man[q].feature[kk],
                                                  man[q].normal[kk], q < p || (q == p && kk < k));
            }
            for (int q = from; q < to && !drop; q++) {
                const sd_manifold *o = &man[q];
                int tq = pairs[q].b;
                for (int kk = 0; kk < o->n && !drop; kk++) {
                    if (q == p && kk == k) continue;
                    int fo = o->feature[kk];
                    int tfo = fo & ((1 << SD_TRI_FEATURE_BITS) - 1);
                    if ((fo >> SD_TRI_FEATURE_BITS) != part) continue;
                    if (tfo == SD_TRI_FACE) {
                        drop = is_edge ? tri_has_edge(wl, tq, id) : tri_has_vert(wl, tq, id);
                    } else if (tfo < SD_TRI_VERT0) {
                        if (is_edge) {
                            /* the same edge seen from the other triangle: keep the first */
                            drop = (q < p || (q == p && kk < k)) && tri_feature_gid(wl, tq, fo) == gid;
                        } else {
                            int32_t e = wl->edge_id[tq][tfo - SD_TRI_EDGE0];
                            drop = wl->edge_vert[e][0] == id || wl->edge_vert[e][1] == id;
                        }
                    } else if (!is_edge) {
                        drop = (q < p || (q == p && kk < k)) && tri_feature_gid(wl, tq, fo) == gid;
                    }
                }
            }
            if (drop) {
                /* mark dropped with overlap 0; compacted below */
                m->overlap[k] = -1.0;
            }
        }
    }
    for (int p = from; p < to; p++) {
        sd_manifold *m = &man[p];
        int j = 0;
        for (int k = 0; k < m->n; k++) {
            if (m->overlap[k] < 0.0) continue;
            if (j != k) {
                m->normal[j] = m->normal[k];
                m->point[j] = m->point[k];
                m->overlap[j] = m->overlap[k];
                m->feature[j] = m->feature[k];
                m->share[j] = m->share[k];
            }
            j++;
        }
        m->n = j;
    }
}
