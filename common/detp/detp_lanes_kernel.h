/* detp_lanes_kernel: the body of gi_detp_lanes_estimate for one vector
 * width (detp_lanes.c includes it once per instruction set). Defines
 * LANES_FN(cx..nz SoA of n discs padded to LANES_W, r2, segments, acc, st);
 * the includer defines LANES_FN, LANES_W, LANES_VF, LANES_VI (type names),
 * LANES_ATTR and LANES_MOVEMASK, which the end of this file undefines.
 *
 * Each lane does gi_detp_crosses' arithmetic, operation for operation and
 * in its order (packed IEEE operations round like scalar ones; nothing is
 * contracted into fused multiply-adds), so every width finds basic DETP's
 * pairs. The tests are combined without branches: with discs in mesh
 * order the back-face test flips from group to group, and its branch
 * mispredicted more often than not. */
typedef float LANES_VF __attribute__((vector_size(4 * LANES_W), aligned(4)));
typedef int32_t LANES_VI __attribute__((vector_size(4 * LANES_W)));

LANES_ATTR static void LANES_FN(const float *cx, const float *cy, const float *cz,
                                const float *nx, const float *ny, const float *nz, size_t n,
                                float r2s, const gi_detp_segments *s, gi_detp_accum *acc,
                                gi_detp_stats *st)
{
    const LANES_VF zero = {0}, r2 = zero + r2s;
    uint64_t crossings = 0;
    for (size_t j = 0; j < s->count; j++) {
        const gi_detp_segment *g = &s->v[j];
        const LANES_VF ox = zero + g->org.x, oy = zero + g->org.y, oz = zero + g->org.z,
                       dx = zero + g->dir.x, dy = zero + g->dir.y, dz = zero + g->dir.z,
                       t_end = zero + g->t_end;
        for (size_t i = 0; i < n; i += LANES_W) {
            LANES_VF vnx = *(const LANES_VF *)(nx + i), vny = *(const LANES_VF *)(ny + i),
                     vnz = *(const LANES_VF *)(nz + i), vcx = *(const LANES_VF *)(cx + i),
                     vcy = *(const LANES_VF *)(cy + i), vcz = *(const LANES_VF *)(cz + i);
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
            while (hit) {
                unsigned k = (unsigned)__builtin_ctz(hit);
                hit &= hit - 1;
                gi_detp_accum_add(acc, (uint32_t)(i + k), g);
                crossings++;
            }
        }
    }
    st->crossings += crossings;
}
#undef LANES_FN
#undef LANES_W
#undef LANES_VF
#undef LANES_VI
#undef LANES_ATTR
#undef LANES_MOVEMASK
