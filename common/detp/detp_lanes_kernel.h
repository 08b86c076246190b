/* detp_lanes_kernel: the body of gi_detp_lanes_estimate for one vector
 * width (detp_lanes.c includes it once per instruction set). Defines
 * LANES_FN(const lanes_set *, segments, acc, st); the includer defines
 * LANES_FN, LANES_W, LANES_VF, LANES_VI (type names), LANES_ATTR and
 * LANES_MOVEMASK, which the end of this file undefines.
 *
 * Per segment, first the groups (LANES_W discs each, near one another):
 * a group is skipped when every disc in it faces away from the segment or
 * the segment passes too far from it (both with margins far above
 * rounding, so no crossing is lost). Then each disc of a kept group does
 * gi_detp_crosses' arithmetic, operation for operation and in its order
 * (packed IEEE operations round like scalar ones; nothing is contracted
 * into fused multiply-adds), so every width finds basic DETP's pairs. The
 * tests are combined without branches: the back-face test flips from disc
 * to disc, and its branch mispredicted more often than not. */
typedef float LANES_VF __attribute__((vector_size(4 * LANES_W), aligned(4)));
typedef int32_t LANES_VI __attribute__((vector_size(4 * LANES_W)));
typedef int64_t LANES_VL __attribute__((vector_size(8 * LANES_W), aligned(8)));
typedef uint32_t LANES_VU __attribute__((vector_size(4 * LANES_W), aligned(4)));

LANES_ATTR static void LANES_FN(const lanes_set *d, const gi_detp_segments *s,
                                gi_detp_accum *acc, gi_detp_stats *st)
{
    const LANES_VF zero = {0}, r2 = zero + d->r2;
    uint64_t crossings = 0, tests = 0;
    /* Fixed point: the sums per lane, added in vectors (integer sums do
     * not depend on the order) and into acc at the end. */
    size_t nl = d->groups * LANES_W;
    int64_t *se = acc->fixed ? gi_xcalloc(3 * nl + 1, sizeof *se) : NULL;
    uint32_t *sh = acc->fixed ? gi_xcalloc(nl + 1, sizeof *sh) : NULL;
#define LOAD(p, i) (*(const LANES_VF *)((p) + (i)))
    for (size_t j = 0; j < s->count; j++) {
        const gi_detp_segment *g = &s->v[j];
        const LANES_VF ox = zero + g->org.x, oy = zero + g->org.y, oz = zero + g->org.z,
                       dx = zero + g->dir.x, dy = zero + g->dir.y, dz = zero + g->dir.z,
                       t_end = zero + g->t_end;
        /* The segment's fixed-point contribution, converted once for all
         * the discs it crosses. */
        const gi_detp_fixed_contrib c =
            acc->fixed ? gi_detp_fixed_contrib_of(acc, g) : (gi_detp_fixed_contrib){{0}, 0};
        const LANES_VL c0 = (LANES_VL){0} + c.e[0], c1 = (LANES_VL){0} + c.e[1],
                       c2 = (LANES_VL){0} + c.e[2];
        const LANES_VU ch = (LANES_VU){0} + c.hit;
        for (size_t G = 0; G < d->groups; G += LANES_W) {
            /* Faces away: dir . axis >= sin(cone half-angle). */
            LANES_VI back = (dx * LOAD(d->ax, G) + dy * LOAD(d->ay, G)) + dz * LOAD(d->az, G) >=
                            LOAD(d->sin_t, G);
            /* The segment's point nearest the group's centre. */
            LANES_VF qx = LOAD(d->gx, G) - ox, qy = LOAD(d->gy, G) - oy, qz = LOAD(d->gz, G) - oz;
            LANES_VF tc = (qx * dx + qy * dy) + qz * dz;
            LANES_VI below = tc < zero, beyond = tc > t_end; /* clamp to [0, t_end] */
            tc = (LANES_VF)(((LANES_VI)tc & ~below & ~beyond) | ((LANES_VI)t_end & beyond));
            qx -= dx * tc, qy -= dy * tc, qz -= dz * tc;
            LANES_VI far = (qx * qx + qy * qy) + qz * qz > LOAD(d->reach2, G);
            unsigned keep = (unsigned)LANES_MOVEMASK(~(back | far)) & ((1u << LANES_W) - 1u);
            while (keep) {
                size_t i = (G + (unsigned)__builtin_ctz(keep)) * LANES_W;
                keep &= keep - 1;
                tests += LANES_W;
                LANES_VF vnx = LOAD(d->nx, i), vny = LOAD(d->ny, i), vnz = LOAD(d->nz, i),
                         vcx = LOAD(d->cx, i), vcy = LOAD(d->cy, i), vcz = LOAD(d->cz, i);
                /* denom = dir . n; t = ((c - org) . n) / denom */
                LANES_VF denom = (dx * vnx + dy * vny) + dz * vnz;
                LANES_VF num = ((vcx - ox) * vnx + (vcy - oy) * vny) + (vcz - oz) * vnz;
                LANES_VF t = num / denom;
                /* p = (org + dir t) - c; |p|^2 <= r2 */
                LANES_VF px = (ox + dx * t) - vcx, py = (oy + dy * t) - vcy,
                         pz = (oz + dz * t) - vcz;
                LANES_VF p2 = (px * px + py * py) + pz * pz;
                LANES_VI ok = (denom < zero) & (t > zero) & (t < t_end) & (p2 <= r2);
                unsigned hit = (unsigned)LANES_MOVEMASK(ok);
                crossings += (uint64_t)__builtin_popcount(hit);
                if (se) {
                    const LANES_VL okl = __builtin_convertvector(ok, LANES_VL);
                    *(LANES_VL *)(se + i) += okl & c0;
                    *(LANES_VL *)(se + nl + i) += okl & c1;
                    *(LANES_VL *)(se + 2 * nl + i) += okl & c2;
                    *(LANES_VU *)(sh + i) += (LANES_VU)ok & ch;
                    continue;
                }
                while (hit) {
                    unsigned k = (unsigned)__builtin_ctz(hit);
                    hit &= hit - 1;
                    gi_detp_accum_add(acc, d->idx[i + k], g);
                }
            }
        }
    }
#undef LOAD
    if (se) {
        /* Padding lanes cross nothing: their zeros go to disc 0. */
        for (size_t i = 0; i < nl; i++) {
            int64_t *f = &acc->fixed[3 * (size_t)d->idx[i]];
            f[0] += se[i];
            f[1] += se[nl + i];
            f[2] += se[2 * nl + i];
            acc->hits[d->idx[i]] += sh[i];
        }
        free(se);
        free(sh);
    }
    st->crossings += crossings;
    st->disc_tests += tests;
}
#undef LANES_FN
#undef LANES_W
#undef LANES_VF
#undef LANES_VI
#undef LANES_VL
#undef LANES_VU
#undef LANES_ATTR
#undef LANES_MOVEMASK
