/* Example program of an exported symmech model: runs the scene from its start values (DOP853, or Radau IIA
   with dense output for a stiff model) and prints the native run's main table (TABLE_HEADER, one row per
   output time) as CSV. Hand-written; the physics is the generated module. Build with `make`, run
   `./example`. */
#include <stdio.h>

#include "symmech_model.h"

/* the model's notices (a rocking contact, the stop at max_impacts) on stderr */
static void notice(void *env, double t, const char *message)
{
    (void)env;
    fprintf(stderr, "%s: t = %.17g s: %s\n", MODEL_IDENTIFIER, t, message);
}

int main(void)
{
    static const int columns[] = TABLE_VRS;
    static SymmechModel model;  /* zeroed: no notice environment */
    symmech_reset(&model);
    model.notice = notice;
    model.horizon = TABLE_STOP;  /* no inputs change on the way: steps need not stop at the printed times */
    if (symmech_start(&model) != 0) {
        fprintf(stderr, "%s: singular mass matrix or non-finite rates at the start\n", MODEL_IDENTIFIER);
        return 1;
    }
    printf("%s\n", TABLE_HEADER);
    for (int k = 0; k <= TABLE_STEPS; k++) {
        double t = k == TABLE_STEPS ? TABLE_STOP : TABLE_STOP / TABLE_STEPS * k;
        int status = symmech_integrate(&model, t, EXAMPLE_RTOL, EXAMPLE_ATOL);
        if (status == 1) return 0;  /* the model ended the run (its notice printed) */
        if (status != 0) {
            fprintf(stderr, "%s: the integration failed at t = %g s\n", MODEL_IDENTIFIER, t);
            return 1;
        }
        printf("%.17g", t);
        for (size_t i = 0; i < sizeof columns / sizeof columns[0]; i++) printf(",%.17g", model.r[columns[i]]);
        printf("\n");
    }
    return 0;
}
