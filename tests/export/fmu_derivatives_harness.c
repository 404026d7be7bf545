/* ASan/UBSan harness of an FMI 3.0 FMU's derivatives (tests/export/test_fmu_derivatives.py): compiled with
   -DMODEL_C='"<id>.c"' and the FMU's sources; every directional and adjoint derivative in Model Exchange
   and (after a step) Co-Simulation, the adjoint identity, bad calls refused; exit status 0 when all hold */
#include MODEL_C
static void logm(fmi3InstanceEnvironment e, fmi3Status s, fmi3String cat, fmi3String msg)
{ (void)e; (void)cat; if (s != fmi3OK) fprintf(stderr, "  [log %d] %s\n", (int)s, msg); }
static int run(int cs)
{
    fmi3Instance c = cs ? fmi3InstantiateCoSimulation("h", GUID, "", 0, 1, 0, 0, NULL, 0, NULL, logm, NULL)
                        : fmi3InstantiateModelExchange("h", GUID, "", 0, 1, NULL, logm);
    unsigned unk[NXS + NOV], kn[NXS + NIN + 1];
    double seed[NXS + NOV + NIN], sens[NXS + NOV + NIN], dot1 = 0, dot2 = 0;
    size_t nu = 0, nk = 0, i;
    int bad = 0;
    if (!c) return 1;
    fmi3EnterInitializationMode(c, 0, 0, 0.0, 0, 0);
    fmi3ExitInitializationMode(c);
    if (cs) {
        bool a, b, d;
        double t;
        if (fmi3DoStep(c, 0.0, 0.2, 1, &a, &b, &d, &t) != fmi3OK) return 6;
    }
    for (i = 0; i < NXS; i++) unk[nu++] = VR_DX + i;
    for (i = 0; i < NOV; i++) {
        int skip = 0, k;
        for (k = 0; k < MBD_NSKIP; k++) skip |= MBD_SKIP[k] == (int)i;
        if (!skip) unk[nu++] = VR_OUT + i;
    }
    for (i = 0; i < NXS; i++) kn[nk++] = VR_X + i;
    for (i = 0; i < NIN; i++) kn[nk++] = VR_IN + i;
    for (i = 0; i < nk; i++) seed[i] = 0.3 + 0.1 * i;
    if (fmi3GetDirectionalDerivative(c, unk, nu, kn, nk, seed, nk, sens, nu) != fmi3OK) return 2;
    for (i = 0; i < nu; i++) dot1 += (1.0 - 0.01 * i) * sens[i];
    for (i = 0; i < nu; i++) seed[i] = 1.0 - 0.01 * i;
    if (fmi3GetAdjointDerivative(c, unk, nu, kn, nk, seed, nu, sens, nk) != fmi3OK) return 3;
    for (i = 0; i < nk; i++) dot2 += (0.3 + 0.1 * i) * sens[i];
    printf("%s: %zu unknowns, %zu knowns, <w,Jv> = %.17g, <J^T w,v> = %.17g, rel %.2e\n", cs ? "CS" : "ME", nu, nk,
           dot1, dot2, fabs(dot1 - dot2) / fabs(dot1));
    if (!(fabs(dot1 - dot2) <= 1e-12 * fabs(dot1))) return 5;
    /* bad calls: an unknown reference, wrong sizes, NULL arrays */
    { unsigned p = 0; bad += fmi3GetDirectionalDerivative(c, unk, 1, &p, 1, seed, 1, sens, 1) == fmi3Error; }
    { unsigned p = 999999; bad += fmi3GetDirectionalDerivative(c, &p, 1, kn, 1, seed, 1, sens, 1) == fmi3Error; }
    bad += fmi3GetAdjointDerivative(c, unk, 2, kn, nk, seed, 2, sens, 2) == fmi3Error;
    bad += fmi3GetDirectionalDerivative(c, unk, 2, NULL, 1, seed, 1, sens, 2) == fmi3Error;
    bad += fmi3GetDirectionalDerivative(c, unk, 0, kn, 1, seed, 1, sens, 0) == fmi3OK;
    printf("  bad calls refused: %d of 5\n", bad);
    fmi3FreeInstance(c);
    return bad == 5 ? 0 : 4;
}
int main(void) { return run(0) * 10 + run(1); }
