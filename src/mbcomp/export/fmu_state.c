/* mbcomp FMU states: what fmi3GetFMUState / fmi2GetFMUstate save and SetFMUState restores, and
 * their serialization (included at the end of fmu_core.c; the wrappers fmi3.c, fmi2.c call in).
 *
 * A state is every value that decides the instance's future: the time, [q, u], the start values
 * and parameters (and whether the starts changed), the inputs and Baumgarte gains, the
 * Co-Simulation tolerance (and whether it was set), the FMI mode, the counters, and with SELECT
 * the Model Exchange states x with their partition dep/ind, growth, event_due, x_dirty. Not in
 * it: the name, the logger, pointers and work arrays (the hoisted values are recomputed from the
 * parameters: a restore marks them dirty; every Co-Simulation step starts DOP853 afresh).
 *
 * The serialized form (format 2: 2 added the user events' records): every number an unsigned 64-bit little-endian word (a double
 * by its bits, an int by its value), in this order --
 *   header:  the signature "mbcompFS" (8 bytes), the format, the total size in bytes, the FMU's
 *            instantiation token (64 bytes, NUL-padded), then cs, NQ, NU, NXS, NP, NIN, MM, NI,
 *            SELECT, MECH (the sizes the values below have);
 *   values:  mb_state_walk's order;
 *   end:     FNV-1a 64 of every byte before it.
 * Deserializing checks each of these before it uses a value, never reads past the size given,
 * and checks the values that index arrays (the partition) or pick code paths (mode, flags). */
#include <limits.h>
#include <stdint.h>

#define MB_STATE_MAGIC 0x6d62636fu /* a live state object of this FMU */
#define MB_STATE_FORMAT 2u
#define MB_TOKEN_BYTES 64
#define MB_NDIMS 10
#define MB_HEAD_BYTES (8 + 8 + 8 + MB_TOKEN_BYTES + 8 * MB_NDIMS)
static const char MB_STATE_SIG[8] = {'m', 'b', 'c', 'o', 'm', 'p', 'F', 'S'};

typedef struct {
    uint32_t magic;  /* MB_STATE_MAGIC while allocated */
    uint64_t token;  /* FNV-1a 64 of the instantiation token of the FMU that made it */
    int cs, mode, starts_changed, tol_set;
    double t, alpha, beta, rtol;
    double p[NP + 1], y[NX + 1], y0[NX + 1], d[2 + NIN];
    int pfree[NU + 1], vfree[NU + 1], set[NX + 1]; /* what initialization may move, the starts set */
#if MECH
    int projections;
#endif
#if SELECT
    double x[NXS + 1], growth;
    int dep[MM + 1], ind[NI + 1], x_dirty, event_due, repartitions;
#endif
#if HYBRID
    /* the active set and what the next events depend on (fmu_events.c): modes, the recent impacts'
       times for the rest rule, each component's last event, Co-Simulation's located event */
    int hy_mode[HY_NCOMP + 1], hy_nhits[HY_NCOMP + 1], hy_dir[HY_NZ + 1], hy_fresh;
    double hy_hits[(HY_NCOMP + 1) * (HY_CHATTER + 2)], hy_last[HY_NCOMP + 1], hy_events;
    /* the user events: firings, Model Exchange's sides (+1), last firings, the run ended */
    int hy_ue_n[HY_NUE + 1], hy_ue_side[HY_NUE + 1], hy_ended;
    double hy_ue_last[HY_NUE + 1];
#endif
} mb_state;

static uint64_t mb_fnv(const unsigned char *b, size_t n)
{
    uint64_t h = 0xcbf29ce484222325ull;
    size_t i;
    for (i = 0; i < n; i++) { h ^= b[i]; h *= 0x100000001b3ull; }
    return h;
}

static uint64_t mb_token_hash(void) { return mb_fnv((const unsigned char *)GUID, strlen(GUID)); }

/* a cursor over a serialized state: writes to out, reads from in, or (both NULL) counts; a
   read or write past cap sets over and does nothing */
typedef struct {
    unsigned char *out;
    const unsigned char *in;
    size_t pos, cap;
    int over, bad; /* bad: an int out of range read */
} mb_io;

static void io_raw(mb_io *io, void *v, size_t k)
{
    if (io->over || k > io->cap - io->pos) { io->over = 1; return; }
    if (io->out) memcpy(io->out + io->pos, v, k);
    else if (io->in) memcpy(v, io->in + io->pos, k);
    io->pos += k;
}

static void io_u64(mb_io *io, uint64_t *v)
{
    unsigned char b[8];
    int k;
    if (io->out) for (k = 0; k < 8; k++) b[k] = (unsigned char)(*v >> (8 * k));
    io_raw(io, b, 8);
    if (io->in && !io->over) {
        uint64_t r = 0;
        for (k = 0; k < 8; k++) r |= (uint64_t)b[k] << (8 * k);
        *v = r;
    }
}

static void io_f64(mb_io *io, double *v, int n)
{
    int i;
    for (i = 0; i < n; i++) {
        uint64_t u;
        memcpy(&u, &v[i], sizeof u);
        io_u64(io, &u);
        if (io->in && !io->over) memcpy(&v[i], &u, sizeof u);
    }
}

/* non-negative ints (modes, flags, indices, counters) */
static void io_int(mb_io *io, int *v, int n)
{
    int i;
    for (i = 0; i < n; i++) {
        uint64_t u = (uint64_t)(v[i] < 0 ? 0 : v[i]);
        io_u64(io, &u);
        if (io->in && !io->over) {
            if (u > (uint64_t)INT_MAX) io->bad = 1;
            else v[i] = (int)u;
        }
    }
}

/* the values of a state, in their serialized order */
static void mb_state_walk(mb_io *io, mb_state *s)
{
    io_int(io, &s->mode, 1);
    io_int(io, &s->starts_changed, 1);
    io_int(io, &s->tol_set, 1);
    io_f64(io, &s->t, 1);
    io_f64(io, &s->alpha, 1);
    io_f64(io, &s->beta, 1);
    io_f64(io, &s->rtol, 1);
    io_f64(io, s->p, NP);
    io_f64(io, s->y, NX);
    io_f64(io, s->y0, NX);
    io_int(io, s->pfree, NU);
    io_int(io, s->vfree, NU);
    io_int(io, s->set, NX);
    io_f64(io, s->d, 2 + NIN);
#if MECH
    io_int(io, &s->projections, 1);
#endif
#if SELECT
    io_f64(io, s->x, NXS);
    io_f64(io, &s->growth, 1);
    io_int(io, s->dep, MM);
    io_int(io, s->ind, NI);
    io_int(io, &s->x_dirty, 1);
    io_int(io, &s->event_due, 1);
    io_int(io, &s->repartitions, 1);
#endif
#if HYBRID
    io_int(io, s->hy_mode, HY_NCOMP);
    io_int(io, s->hy_nhits, HY_NCOMP);
    io_int(io, s->hy_dir, HY_NZ);
    io_int(io, &s->hy_fresh, 1);
    io_f64(io, s->hy_hits, (HY_NCOMP + 1) * (HY_CHATTER + 2));
    io_f64(io, s->hy_last, HY_NCOMP);
    io_f64(io, &s->hy_events, 1);
    io_int(io, s->hy_ue_n, HY_NUE);
    io_int(io, s->hy_ue_side, HY_NUE);
    io_int(io, &s->hy_ended, 1);
    io_f64(io, s->hy_ue_last, HY_NUE);
#endif
}

/* the header of a serialized state: what it is and the sizes of its values */
typedef struct {
    char sig[8];
    uint64_t format, size;
    char token[MB_TOKEN_BYTES];
    uint64_t dims[MB_NDIMS];
} mb_head;

static void mb_head_walk(mb_io *io, mb_head *h)
{
    int k;
    io_raw(io, h->sig, sizeof h->sig);
    io_u64(io, &h->format);
    io_u64(io, &h->size);
    io_raw(io, h->token, sizeof h->token);
    for (k = 0; k < MB_NDIMS; k++) io_u64(io, &h->dims[k]);
}

static const char *const MB_DIM_NAMES[MB_NDIMS] = {"cs", "NQ", "NU", "NXS", "NP", "NIN", "MM", "NI", "SELECT", "MECH"};

/* this FMU's header for a state of an instance of kind cs (size: the serialized size) */
static void mb_head_of(mb_head *h, int cs, size_t size)
{
    uint64_t dims[MB_NDIMS] = {(uint64_t)cs, NQ, NU, NXS, NP, NIN, 0, 0, SELECT, MECH};
#if SELECT
    dims[6] = MM;
    dims[7] = NI;
#endif
    memset(h, 0, sizeof *h);
    memcpy(h->sig, MB_STATE_SIG, sizeof h->sig);
    h->format = MB_STATE_FORMAT;
    h->size = size;
    strncpy(h->token, GUID, MB_TOKEN_BYTES - 1);
    memcpy(h->dims, dims, sizeof dims);
}

/* the serialized size of a state (the same for every state of this FMU) */
static size_t mb_state_bytes(void)
{
    mb_state s;
    mb_head h;
    mb_io io = {NULL, NULL, 0, (size_t)-1, 0, 0};
    memset(&s, 0, sizeof s);
    memset(&h, 0, sizeof h);
    mb_head_walk(&io, &h);
    mb_state_walk(&io, &s);
    return io.pos + 8; /* + the checksum */
}

/* the state object behind a handle: NULL (after logging) for none or one not made by this FMU */
static mb_state *mb_state_of(Inst *c, const void *handle, const char *fn)
{
    mb_state *s = (mb_state *)handle;
    if (!s) { say(c, 1, "%s: no FMU state given (NULL)", fn); return NULL; }
    if (s->magic != MB_STATE_MAGIC || s->token != mb_token_hash()) {
        say(c, 1, "%s: the FMU state was not made by this FMU (or was freed)", fn);
        return NULL;
    }
    return s;
}

static void mb_state_take(const Inst *c, mb_state *s)
{
    s->magic = MB_STATE_MAGIC;
    s->token = mb_token_hash();
    s->cs = c->cs;
    s->mode = c->mode;
    s->starts_changed = c->starts_changed;
    s->tol_set = c->tol_set;
    s->t = c->t;
    s->alpha = c->alpha;
    s->beta = c->beta;
    s->rtol = c->rtol;
    memcpy(s->p, c->p, sizeof s->p);
    memcpy(s->y, c->y, sizeof s->y);
    memcpy(s->y0, c->y0, sizeof s->y0);
    memcpy(s->d, c->d, sizeof s->d);
    {
        int k;
        for (k = 0; k < NU; k++) { s->pfree[k] = c->pfree[k]; s->vfree[k] = c->vfree[k]; }
        for (k = 0; k < NX; k++) s->set[k] = c->set[k];
    }
#if MECH
    s->projections = c->projections;
#endif
#if SELECT
    memcpy(s->x, c->x, sizeof s->x);
    s->growth = c->growth;
    memcpy(s->dep, c->dep, sizeof s->dep);
    memcpy(s->ind, c->ind, sizeof s->ind);
    s->x_dirty = c->x_dirty;
    s->event_due = c->event_due;
    s->repartitions = c->repartitions;
#endif
#if HYBRID
    {
        int k, j;
        for (k = 0; k < HY_NCOMP; k++) {
            s->hy_mode[k] = c->hy.mode[k];
            s->hy_nhits[k] = c->hy.nhits[k];
            s->hy_last[k] = c->hy.last[k];
        }
        for (k = 0; k <= HY_NCOMP; k++)
            for (j = 0; j < HY_CHATTER + 2; j++) s->hy_hits[k * (HY_CHATTER + 2) + j] = c->hy.hits[k][j];
        for (k = 0; k < HY_NZ; k++) s->hy_dir[k] = c->hy.dir[k] + 1; /* kept >= 0 (serialized unsigned) */
        s->hy_fresh = c->hy.fresh + 1;
        s->hy_events = (double)c->hy.events;
        for (k = 0; k < HY_NUE; k++) {
            s->hy_ue_n[k] = c->hy.ue_n[k];
            s->hy_ue_side[k] = c->hy.ue_side[k] + 1;
            s->hy_ue_last[k] = c->hy.ue_last[k];
        }
        s->hy_ended = c->hy.ended;
    }
#endif
}

/* GetFMUState: *handle NULL -> a new state; else the caller's earlier state, overwritten */
static int mb_state_get(Inst *c, void **handle)
{
    mb_state *s;
    if (!handle) { say(c, 1, "GetFMUState: nowhere to put the state (NULL)"); return -1; }
    if (*handle) {
        s = mb_state_of(c, *handle, "GetFMUState");
        if (!s) return -1;
    } else {
        s = (mb_state *)calloc(1, sizeof *s);
        if (!s) { say(c, 1, "GetFMUState: out of memory (%zu bytes)", sizeof *s); return -1; }
    }
    mb_state_take(c, s);
    *handle = s;
    return 0;
}

/* SetFMUState: the instance continues from the state (its hoisted values recomputed) */
static int mb_state_set(Inst *c, const void *handle)
{
    const mb_state *s = mb_state_of(c, handle, "SetFMUState");
    if (!s) return -1;
    if (s->cs != c->cs) {
        say(c, 1, "SetFMUState: a %s state cannot be set in a %s instance", s->cs ? "Co-Simulation" : "Model Exchange",
            c->cs ? "Co-Simulation" : "Model Exchange");
        return -1;
    }
    c->mode = s->mode;
    c->starts_changed = s->starts_changed;
    c->tol_set = s->tol_set;
    c->t = s->t;
    c->alpha = s->alpha;
    c->beta = s->beta;
    c->rtol = s->rtol;
    memcpy(c->p, s->p, sizeof s->p);
    memcpy(c->y, s->y, sizeof s->y);
    memcpy(c->y0, s->y0, sizeof s->y0);
    memcpy(c->d, s->d, sizeof s->d);
    {
        int k;
        for (k = 0; k < NU; k++) { c->pfree[k] = (unsigned char)s->pfree[k]; c->vfree[k] = (unsigned char)s->vfree[k]; }
        for (k = 0; k < NX; k++) c->set[k] = (unsigned char)s->set[k];
    }
#if MECH
    c->projections = s->projections;
#endif
#if SELECT
    memcpy(c->x, s->x, sizeof s->x);
    c->growth = s->growth;
    memcpy(c->dep, s->dep, sizeof s->dep);
    memcpy(c->ind, s->ind, sizeof s->ind);
    c->x_dirty = s->x_dirty;
    c->event_due = s->event_due;
    c->repartitions = s->repartitions;
#endif
#if HYBRID
    {
        int k, j;
        for (k = 0; k < HY_NCOMP; k++) {
            c->hy.mode[k] = s->hy_mode[k];
            c->hy.nhits[k] = s->hy_nhits[k];
            c->hy.last[k] = s->hy_last[k];
        }
        for (k = 0; k <= HY_NCOMP; k++)
            for (j = 0; j < HY_CHATTER + 2; j++) c->hy.hits[k][j] = s->hy_hits[k * (HY_CHATTER + 2) + j];
        for (k = 0; k < HY_NZ; k++) c->hy.dir[k] = s->hy_dir[k] - 1;
        c->hy.fresh = s->hy_fresh - 1;
        c->hy.events = (long)s->hy_events;
        for (k = 0; k < HY_NUE; k++) {
            c->hy.ue_n[k] = s->hy_ue_n[k];
            c->hy.ue_side[k] = s->hy_ue_side[k] - 1;
            c->hy.ue_last[k] = s->hy_ue_last[k];
        }
        c->hy.ended = s->hy_ended;
    }
#endif
    c->dirty = 1; /* the hoisted values: recomputed from the parameters at the next use */
    return 0;
}

/* FreeFMUState: frees *handle and sets it NULL (a NULL *handle: nothing to do) */
static int mb_state_free(Inst *c, void **handle)
{
    mb_state *s;
    if (!handle) { say(c, 1, "FreeFMUState: no state pointer given (NULL)"); return -1; }
    if (!*handle) return 0;
    s = mb_state_of(c, *handle, "FreeFMUState");
    if (!s) return -1;
    s->magic = 0;
    free(s);
    *handle = NULL;
    return 0;
}

static int mb_state_size(Inst *c, const void *handle, size_t *n)
{
    if (!mb_state_of(c, handle, "SerializedFMUStateSize")) return -1;
    if (!n) { say(c, 1, "SerializedFMUStateSize: nowhere to put the size (NULL)"); return -1; }
    *n = mb_state_bytes();
    return 0;
}

static int mb_state_serialize(Inst *c, const void *handle, unsigned char *buf, size_t n)
{
    mb_state *s = mb_state_of(c, handle, "SerializeFMUState");
    size_t need = mb_state_bytes();
    mb_head h;
    mb_io io = {buf, NULL, 0, n, 0, 0};
    uint64_t sum;
    if (!s) return -1;
    if (!buf || n < need) {
        say(c, 1, "SerializeFMUState: %zu bytes given, the state needs %zu (SerializedFMUStateSize)", buf ? n : 0, need);
        return -1;
    }
    mb_head_of(&h, s->cs, need);
    mb_head_walk(&io, &h);
    mb_state_walk(&io, s);
    sum = mb_fnv(buf, io.pos);
    io_u64(&io, &sum);
    if (io.over || io.pos != need) { say(c, 1, "SerializeFMUState: internal size mismatch"); return -1; }
    return 0;
}

/* whether the values read are a state this FMU can continue from; logs what is wrong */
static int mb_state_check(Inst *c, const mb_state *s)
{
#if SELECT
    int seen[NU + 1], k, ok = 1;
    memset(seen, 0, sizeof seen);
    for (k = 0; k < MM; k++) {
        ok = ok && s->dep[k] < NU && !seen[s->dep[k]];
        if (ok) seen[s->dep[k]] = 1;
    }
    for (k = 0; k < NI; k++) {
        ok = ok && s->ind[k] < NU && !seen[s->ind[k]];
        if (ok) seen[s->ind[k]] = 1;
    }
    if (!ok) { say(c, 1, "DeserializeFMUState: the partition of the speeds is not one (a corrupted buffer)"); return -1; }
    if (s->x_dirty > 1 || s->event_due > 1) {
        say(c, 1, "DeserializeFMUState: a flag is neither 0 nor 1 (a corrupted buffer)");
        return -1;
    }
#endif
    if (s->mode > M_ERROR || s->starts_changed > 1 || s->tol_set > 1) {
        say(c, 1, "DeserializeFMUState: the mode or a flag is out of range (a corrupted buffer)");
        return -1;
    }
#if HYBRID
    {
        int k, ok = s->hy_fresh >= 0 && s->hy_fresh <= HY_NZ && isfinite(s->hy_events) && s->hy_events >= 0.0;
        for (k = 0; k < HY_NCOMP; k++)
            ok = ok && s->hy_mode[k] >= 0 && s->hy_mode[k] <= 2 && s->hy_nhits[k] >= 0 &&
                 s->hy_nhits[k] <= HY_CHATTER + 2 && isfinite(s->hy_last[k]);
        for (k = 0; k < HY_NZ; k++) ok = ok && s->hy_dir[k] >= 0 && s->hy_dir[k] <= 2;
        for (k = 0; k < HY_NUE; k++)
            ok = ok && s->hy_ue_n[k] >= 0 && s->hy_ue_side[k] >= 0 && s->hy_ue_side[k] <= 3 && isfinite(s->hy_ue_last[k]);
        ok = ok && s->hy_ended >= 0 && s->hy_ended <= 1;
        for (k = 0; k < (HY_NCOMP + 1) * (HY_CHATTER + 2); k++) ok = ok && !isnan(s->hy_hits[k]);
        if (!ok) {
            say(c, 1, "DeserializeFMUState: a mode or an event record is out of range (a corrupted buffer)");
            return -1;
        }
    }
#endif
    {
        int k, flags_ok = 1;
        for (k = 0; k < NU; k++) flags_ok = flags_ok && s->pfree[k] <= 1 && s->vfree[k] <= 1;
        for (k = 0; k < NX; k++) flags_ok = flags_ok && s->set[k] <= 1;
        if (!flags_ok) {
            say(c, 1, "DeserializeFMUState: a start's fixed flag is neither 0 nor 1 (a corrupted buffer)");
            return -1;
        }
    }
    if (!isfinite(s->t) || !(s->rtol >= 1e-14 && s->rtol < 1.0)) {
        say(c, 1, "DeserializeFMUState: the time %g or the tolerance %g is invalid (a corrupted buffer)", s->t, s->rtol);
        return -1;
    }
    return 0;
}

/* the header's fields against this FMU's: 0, or -1 after saying which differs (the checksum
   was checked before where the size was right: a changed token is a corruption, not another FMU) */
static int mb_head_check(Inst *c, mb_head *h, size_t n)
{
    mb_head mine;
    int k;
    mb_head_of(&mine, c->cs, mb_state_bytes());
    if (memcmp(h->sig, mine.sig, sizeof h->sig) != 0) {
        say(c, 1, "DeserializeFMUState: the bytes are not an mbcomp FMU state (no signature)");
        return -1;
    }
    if (h->format != MB_STATE_FORMAT) {
        say(c, 1, "DeserializeFMUState: a state of format %llu; this FMU reads format %u (another mbcomp version)",
            (unsigned long long)h->format, MB_STATE_FORMAT);
        return -1;
    }
    h->token[MB_TOKEN_BYTES - 1] = '\0';
    if (strcmp(h->token, mine.token) != 0) {
        say(c, 1, "DeserializeFMUState: the state was saved by another FMU (token %s; this FMU's is %s)", h->token,
            GUID);
        return -1;
    }
    if (h->size != n) {
        say(c, 1, "DeserializeFMUState: %zu bytes given, the state says it has %llu (%s)", n,
            (unsigned long long)h->size, h->size > n ? "a truncated buffer" : "a corrupted header");
        return -1;
    }
    for (k = 0; k < MB_NDIMS; k++) {
        if (h->dims[k] != mine.dims[k]) {
            if (k == 0)
                say(c, 1, "DeserializeFMUState: a %s state cannot be set in a %s instance",
                    h->dims[0] ? "Co-Simulation" : "Model Exchange", c->cs ? "Co-Simulation" : "Model Exchange");
            else
                say(c, 1, "DeserializeFMUState: the state has %s = %llu, this FMU %llu (another build of the FMU)",
                    MB_DIM_NAMES[k], (unsigned long long)h->dims[k], (unsigned long long)mine.dims[k]);
            return -1;
        }
    }
    return 0;
}

/* DeserializeFMUState: the state in buf[0..n) into *handle (a new state when NULL) */
static int mb_state_deserialize(Inst *c, const unsigned char *buf, size_t n, void **handle)
{
    mb_head h;
    mb_state tmp, *s;
    mb_io io = {NULL, buf, 0, n, 0, 0};
    uint64_t sum = 0;
    if (!handle || !buf) { say(c, 1, "DeserializeFMUState: no %s given (NULL)", buf ? "state pointer" : "bytes"); return -1; }
    if (n < MB_HEAD_BYTES + 8) {
        say(c, 1, "DeserializeFMUState: %zu bytes are too few for a state (a truncated buffer: this FMU's states "
            "have %zu)", n, mb_state_bytes());
        return -1;
    }
    memset(&h, 0, sizeof h);
    mb_head_walk(&io, &h);
    if (io.over) { say(c, 1, "DeserializeFMUState: a truncated buffer"); return -1; }
    if (memcmp(h.sig, MB_STATE_SIG, sizeof h.sig) == 0 && h.format == MB_STATE_FORMAT && h.size == n) {
        mb_io end = {NULL, buf, n - 8, n, 0, 0};
        io_u64(&end, &sum);
        if (end.over || sum != mb_fnv(buf, n - 8)) {
            say(c, 1, "DeserializeFMUState: the checksum does not match (a corrupted buffer)");
            return -1;
        }
    }
    if (mb_head_check(c, &h, n)) return -1;
    memset(&tmp, 0, sizeof tmp);
    tmp.magic = MB_STATE_MAGIC;
    tmp.token = mb_token_hash();
    tmp.cs = c->cs;
    mb_state_walk(&io, &tmp);
    if (io.over || io.pos + 8 != n) { say(c, 1, "DeserializeFMUState: a truncated buffer"); return -1; }
    if (io.bad) { say(c, 1, "DeserializeFMUState: an integer out of range (a corrupted buffer)"); return -1; }
    if (mb_state_check(c, &tmp)) return -1;
    if (*handle) {
        s = mb_state_of(c, *handle, "DeserializeFMUState");
        if (!s) return -1;
    } else {
        s = (mb_state *)malloc(sizeof *s);
        if (!s) { say(c, 1, "DeserializeFMUState: out of memory (%zu bytes)", sizeof *s); return -1; }
    }
    memcpy(s, &tmp, sizeof tmp);
    *handle = s;
    return 0;
}
