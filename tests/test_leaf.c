/* test_leaf.c - which water arcs of a small rectangle's boundary the union
 * joins inside it (leaf.c). Coordinates in lattice units: the rectangle R
 * is [2560, 2566]^2 (6 x 6 units, 10 pixels from the block's corner), its
 * boundary positions run counter-clockwise from (2560, 2560): bottom 0-6,
 * right 6-12, top 12-18, left 18-24. */
#include "leaf.h"
#include "scene_util.h"
#include "tap.h"

#define U (1.0 / WM_Q) /* a lattice unit, in pixels */
#define X0 2560

/* A river segment from (ax, ay) to (bx, by) (units), radius r (units). */
static void river(wm_scene *s, double ax, double ay, double bx, double by,
                  double r)
{
    const double xy[] = {ax * U, ay * U, bx * U, by * U};
    su_river(s, xy, 2, r * U);
}

/* A lake ring of n points (units). */
static void lake(wm_scene *s, const double *pts, int n)
{
    double xy[32];
    for (int i = 0; i < 2 * n; i++)
        xy[i] = pts[i] * U;
    su_lake(s, xy, &n, 1);
}

/* Labels of R's narc water arcs (pairs in arc[]) in scene s; returns what
 * wm_leaf_join returns. */
static int join(wm_scene *s, int narc, const int64_t *arc, int *label)
{
    su_finish(s);
    wm_probe p;
    if (wm_probe_init(&p, s, 0, 0) != WM_OK)
        return -1;
    const int got = wm_leaf_join(&p, X0, X0, X0 + 6, X0 + 6, narc, arc, label);
    wm_probe_free(&p);
    wm_scene_free(s);
    return got;
}

int main(void)
{
    wm_scene s;
    int label[4];

    /* two rivers a unit wide crossing inside R: one component */
    su_init(&s, 32);
    river(&s, X0 - 20, X0 + 3, X0 + 30, X0 + 3, 0.5);
    river(&s, X0 + 3, X0 - 20, X0 + 3, X0 + 30, 0.5);
    const int64_t cross[] = {2, 4, 8, 10, 14, 16, 20, 22};
    TAP_EQ(join(&s, 4, cross, label), 1, "crossing rivers: read");
    TAP_OK(label[0] == label[1] && label[1] == label[2] && label[2] == label[3],
           "crossing rivers: one component (%d %d %d %d)", label[0], label[1],
           label[2], label[3]);

    /* two parallel rivers a unit wide, 2.5 units apart: two components */
    su_init(&s, 32);
    river(&s, X0 - 20, X0 + 1, X0 + 30, X0 + 1, 0.5);
    river(&s, X0 - 20, X0 + 4, X0 + 30, X0 + 4, 0.5);
    const int64_t par[] = {7, 8, 10, 11, 19, 20, 22, 23};
    TAP_EQ(join(&s, 4, par, label), 1, "parallel rivers: read");
    TAP_OK(label[0] == label[3] && label[1] == label[2] && label[0] != label[1],
           "parallel rivers: apart, each joined across R (%d %d %d %d)",
           label[0], label[1], label[2], label[3]);

    /* two caps meeting inside R: touching (banks that coincide) they stay
     * apart, overlapping they join */
    for (int overlap = 0; overlap < 2; overlap++)
    {
        su_init(&s, 32);
        river(&s, X0 - 20, X0 + 2, X0 + 2, X0 + 2, 1);
        river(&s, X0 + 30, X0 + 2, X0 + 4 - overlap, X0 + 2, 1);
        const int64_t caps[] = {7, 9, 21, 23};
        TAP_EQ(join(&s, 2, caps, label), 1, "caps (overlap %d): read", overlap);
        TAP_OK((label[0] == label[1]) == overlap, "caps %s: %s",
               overlap ? "overlapping" : "touching",
               overlap ? "joined" : "apart");
    }

    /* a lake cut through R by a land notch 2 units wide: two pieces, which
     * a river across the notch joins */
    for (int bridge = 0; bridge < 2; bridge++)
    {
        su_init(&s, 32);
        const double notch[] = {0,      0,       X0 + 2, 0,   X0 + 2, X0 + 10,
                                X0 + 4, X0 + 10, X0 + 4, 0,   5120,   0,
                                5120,   5120,    0,      5120};
        lake(&s, notch, 8);
        if (bridge)
            river(&s, X0 - 20, X0 + 3, X0 + 30, X0 + 3, 0.5);
        const int64_t arcs[] = {4, 14, 16, 26};
        TAP_EQ(join(&s, 2, arcs, label), 1, "lake notch (river %d): read",
               bridge);
        TAP_OK((label[0] == label[1]) == bridge, "lake notch: the pieces %s",
               bridge ? "joined by the river" : "apart");
    }

    /* a lake edge through two corners of R (its diagonal), the lake above
     * it, and a river crossing the lake's part of the top side: read on R
     * grown by a fraction of a unit, one component */
    su_init(&s, 32);
    const double diag[] = {X0 - 10, X0 - 10, X0 + 16,
                           X0 + 16, X0 - 60, X0 + 40};
    lake(&s, diag, 3);
    river(&s, X0 + 5, X0 - 20, X0 + 5, X0 + 30, 0.5);
    const int64_t dg[] = {4, 6, 12, 24};
    TAP_EQ(join(&s, 2, dg, label), 1, "lake edge through R's corners: read");
    TAP_OK(label[0] == label[1], "lake edge through R's corners: joined");

    /* the caller's arcs not matching the inputs' water: left undecided */
    su_init(&s, 32);
    river(&s, X0 - 20, X0 + 1, X0 + 30, X0 + 1, 0.5);
    const int64_t wrong[] = {1, 2, 13, 14};
    TAP_EQ(join(&s, 2, wrong, label), 0, "arcs not the inputs': undecided");
    return TAP_DONE();
}
