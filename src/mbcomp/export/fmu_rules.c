/* mbcomp FMU: what the importer is told by name (included by fmu_core.c after the instance).
 *
 * - the FMI state machine: mb_allowed(c, "fmi3DoStep", S_STEP) refuses a call out of the
 *   modes the standard allows for it, naming the call and the mode;
 * - variable names: mb_name(vr), from the table VAR_NAME[NNAMES] the export writes;
 * - mbcomp's parameter rules (export/rules.py's table RULE_*): a value is checked against its
 *   own rules when it is set (finite; > 0, >= 0, a scalar's != 0), the rules of several
 *   entries (a vector not zero, an inertia tensor, a rotation matrix) at ExitInitializationMode. */

#define S_INST (1u << M_INSTANTIATED)
#define S_INIT (1u << M_INIT)
#define S_EVENT (1u << M_EVENT)
#define S_CONT (1u << M_CONT)
#define S_STEP (1u << M_STEP)
#define S_TERM (1u << M_TERMINATED)
#define S_ANY (S_INST | S_INIT | S_EVENT | S_CONT | S_STEP | S_TERM)

static const char *const MODE_NAME[] = {"Instantiated", "Initialization Mode", "Event Mode", "Continuous-Time Mode",
                                        "Step Mode", "Terminated", "the Error state"};

/* 0 when the instance's mode allows the call fn (mask: the modes the standard allows), else
   -1 after logging the call, the mode it was made in and the modes that allow it */
static int mb_allowed(Inst *c, const char *fn, unsigned mask)
{
    char allowed[160];
    size_t used = 0;
    int m, mode = c->mode;
    if (mode >= 0 && mode <= M_TERMINATED && (mask & (1u << mode))) return 0;
    allowed[0] = '\0';
    for (m = 0; m <= M_TERMINATED; m++) {
        int k;
        if (!(mask & (1u << m))) continue;
        k = snprintf(allowed + used, sizeof allowed - used, "%s%s", used ? ", " : "", MODE_NAME[m]);
        if (k < 0 || (size_t)k >= sizeof allowed - used) break;
        used += (size_t)k;
    }
    say(c, 1, "%s is not allowed in %s (the FMI state machine allows it in: %s)", fn,
        mode >= 0 && mode <= M_ERROR ? MODE_NAME[mode] : "an unknown mode", used ? allowed : "no mode");
    return -1;
}

/* the name of the variable with value reference vr */
static const char *mb_name(unsigned vr)
{
    return vr < (unsigned)NNAMES ? VAR_NAME[vr] : "(no such variable)";
}

enum { RULE_POSITIVE = 1, RULE_NONNEGATIVE = 2, RULE_NONZERO = 3, RULE_INERTIA = 4, RULE_ROTATION = 5 };

/* the rule (index into RULE_*) whose entry is the parameter vr, or -1; *entry its position */
static int mb_rule_of(unsigned vr, int *entry)
{
    int r, k;
    for (r = 0; r < NRULE; r++)
        for (k = 0; k < RULE_LEN[r]; k++)
            if (RULE_VR[RULE_START[r] + k] == (int)vr) { *entry = k; return r; }
    return -1;
}

/* a parameter's value v, when set: 0, or -1 after logging the variable, the value and the rule */
static int mb_check_value(Inst *c, unsigned vr, double v)
{
    int entry = 0, r;
    const char *why = NULL;
    if (!isfinite(v)) {
        say(c, 1, "%s = %g: must be finite (every parameter of an mbcomp model is)", mb_name(vr), v);
        return -1;
    }
    r = mb_rule_of(vr, &entry);
    if (r < 0) return 0;
    if (RULE_KIND[r] == RULE_POSITIVE && !(v > 0.0)) why = "must be > 0";
    if (RULE_KIND[r] == RULE_NONNEGATIVE && !(v >= 0.0)) why = "must be >= 0";
    if (RULE_KIND[r] == RULE_NONZERO && RULE_LEN[r] == 1 && !(v != 0.0)) why = "must not be zero";
    if (!why) return 0;
    say(c, 1, "%s = %g%s%s: %s (the mbcomp rule of %s)", mb_name(vr), v, RULE_UNIT[r][0] ? " " : "", RULE_UNIT[r],
        why, RULE_OWNER[r]);
    return -1;
}

/* the values of rule r's entries (the instance's parameters, or the constants baked in) */
static void mb_rule_values(const Inst *c, int r, double *x, int n)
{
    int k;
    for (k = 0; k < n && k < RULE_LEN[r]; k++) {
        int vr = RULE_VR[RULE_START[r] + k];
        x[k] = vr >= 0 && vr < NP ? c->p[vr] : RULE_CONST[RULE_START[r] + k];
    }
}

/* the eigenvalues of the symmetric 3x3 matrix a (row-major), ascending, into e[3] */
static void mb_sym3_eigenvalues(const double *a, double *e)
{
    double p1 = a[1] * a[1] + a[2] * a[2] + a[5] * a[5], q = (a[0] + a[4] + a[8]) / 3.0;
    double p2 = (a[0] - q) * (a[0] - q) + (a[4] - q) * (a[4] - q) + (a[8] - q) * (a[8] - q) + 2.0 * p1;
    double p = sqrt(p2 / 6.0), b[9], r, phi;
    int k;
    if (!(p > 0.0)) { e[0] = e[1] = e[2] = q; return; }
    for (k = 0; k < 9; k++) b[k] = (a[k] - (k % 4 == 0 ? q : 0.0)) / p;
    r = 0.5 * (b[0] * (b[4] * b[8] - b[5] * b[7]) - b[1] * (b[3] * b[8] - b[5] * b[6])
               + b[2] * (b[3] * b[7] - b[4] * b[6]));
    r = r < -1.0 ? -1.0 : (r > 1.0 ? 1.0 : r);
    phi = acos(r) / 3.0;
    e[2] = q + 2.0 * p * cos(phi);
    e[0] = q + 2.0 * p * cos(phi + 2.0943951023931957);
    e[1] = 3.0 * q - e[0] - e[2];
}

/* why the 3x3 tensor I (kg m^2) is no inertia tensor (mbcomp.modeling.inertia.inertia_problem's
   tests and tolerances), into why[n]; 0 when it is one */
static int mb_inertia_problem(const double *I, char *why, size_t n)
{
    double s[9], e[3], big = 1.0, tol;
    int i, j;
    for (i = 0; i < 9; i++) big = fmax(big, fabs(I[i]));
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            if (fabs(I[3 * i + j] - I[3 * j + i]) > 1e-12 * big + 1e-5 * fabs(I[3 * j + i])) {
                snprintf(why, n, "inertia tensor is not symmetric (I[%d,%d] = %g, I[%d,%d] = %g)", i + 1, j + 1,
                         I[3 * i + j], j + 1, i + 1, I[3 * j + i]);
                return 1;
            }
            s[3 * i + j] = 0.5 * (I[3 * i + j] + I[3 * j + i]);
        }
    mb_sym3_eigenvalues(s, e);
    tol = 1e-12 * fmax(1.0, fmax(fabs(e[0]), fabs(e[2])));
    if (e[0] < -tol) {
        snprintf(why, n, "inertia tensor has a negative principal moment %g kg m^2", e[0]);
        return 1;
    }
    if (e[0] + e[1] < e[2] - tol) {
        snprintf(why, n, "principal moments %g, %g, %g kg m^2 violate the triangle inequality (no real mass "
                 "distribution has them: each must be <= the sum of the other two)", e[0], e[1], e[2]);
        return 1;
    }
    return 0;
}

/* why the 3x3 R is no rotation matrix (orthonormal to 1e-9, determinant +1), into why[n] */
static int mb_rotation_problem(const double *R, char *why, size_t n)
{
    int i, j, k;
    double det;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double d = 0.0;
            for (k = 0; k < 3; k++) d += R[3 * k + i] * R[3 * k + j];
            if (fabs(d - (i == j ? 1.0 : 0.0)) > 1e-9) {
                snprintf(why, n, "not a rotation matrix (R^T R differs from the identity by %g)", d - (i == j));
                return 1;
            }
        }
    det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) + R[2] * (R[3] * R[7] - R[4] * R[6]);
    if (det < 0.0) { snprintf(why, n, "not a rotation matrix (determinant %g: a reflection)", det); return 1; }
    return 0;
}

/* every rule at ExitInitializationMode (the values set one by one were checked when set; a
   rule of several entries needs them all): 0, or -1 after logging the first one broken */
static int mb_check_rules(Inst *c)
{
    int r, k;
    char why[256];
    for (k = 0; k < NP; k++)
        if (mb_check_value(c, (unsigned)k, c->p[k])) return -1;
    for (r = 0; r < NRULE; r++) {
        double x[9] = {0};
        int n = RULE_LEN[r], bad = 0;
        if (n > 9) n = 9;
        mb_rule_values(c, r, x, n);
        why[0] = '\0';
        if (RULE_KIND[r] == RULE_NONZERO) {
            double norm = 0.0;
            for (k = 0; k < n; k++) norm += x[k] * x[k];
            if (!(norm > 0.0)) { snprintf(why, sizeof why, "must not be zero"); bad = 1; }
        } else if (RULE_KIND[r] == RULE_INERTIA && n == 9) {
            bad = mb_inertia_problem(x, why, sizeof why);
        } else if (RULE_KIND[r] == RULE_ROTATION && n == 9) {
            bad = mb_rotation_problem(x, why, sizeof why);
        }
        if (bad) {
            say(c, 1, "%s%s%s: %s (the mbcomp rule of %s)", RULE_NAME[r], RULE_UNIT[r][0] ? " in " : "", RULE_UNIT[r],
                why, RULE_OWNER[r]);
            c->mode = M_ERROR;
            return -1;
        }
    }
    return 0;
}

/* the parameters whose values differ from the export's, "a = 1 (exported: 2), ..." into buf[n]
   (the candidates when a parameter guard fails) */
static void mb_changed_parameters(const Inst *c, char *buf, size_t n)
{
    size_t used = 0;
    int k;
    if (n) buf[0] = '\0';
    for (k = 0; k < NP && used < n; k++) {
        int w;
        if (c->p[k] == P0[k]) continue;
        w = snprintf(buf + used, n - used, "%s%s = %g (exported: %g)", used ? ", " : "", mb_name((unsigned)k), c->p[k],
                     P0[k]);
        if (w < 0 || (size_t)w >= n - used) break;
        used += (size_t)w;
    }
}
