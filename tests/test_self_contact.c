/* test_self_contact.c - self-contact (issue 31, item 1; docs/simulation.md, "Self-contact"):
 * examples/beam_fold.json, a soft beam folded over onto itself, run through `sem run` with
 * self-contact at its default (on) and switched off (contact.self false). Every frame's
 * render mesh is intersected with itself (crossings.h): with self-contact no two of its
 * triangles that were apart at rest ever cross and the folded half rests on the lower one
 * (self contacts reported, the smallest gap above -1 % of the beam's height); without it the
 * same scene crosses (so the check can fail), and a beam whose surface never meets itself
 * gives the same frames with or without it. Also: `contact.self: true` makes contact work
 * for a lone object without colliders, and a wrong value is a one-line error. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "crossings.h"
#include "test_util.h"

static double num(const cJSON *o, const char *key)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(x) ? x->valuedouble : NAN;
}

/* Writes the scene (examples/NAME.json with its frames and contact.self replaced; self: -1
 * leaves it absent) into tmp and runs it into tmp/out_TAG; returns the exit status. */
static int run_scene(const char *name, const char *tag, int frames, int self, const char *tmp, char *dir,
                     size_t dir_size, char *se, size_t se_size)
{
    char path[1024], args[3072];
    snprintf(path, sizeof path, "%s/../../examples/%s.json", SEM_TEST_DATA, name);
    char *text = test_slurp(path, NULL);
    cJSON *scene = text ? cJSON_Parse(text) : NULL;
    free(text);
    CHECK(scene != NULL, "cannot read %s", path);
    if (!scene) return -1;
    cJSON_ReplaceItemInObjectCaseSensitive(scene, "frames", cJSON_CreateNumber(frames));
    if (self >= 0) {
        cJSON *contact = cJSON_CreateObject();
        cJSON_AddBoolToObject(contact, "self", self);
        cJSON_AddItemToObject(scene, "contact", contact);
    }
    snprintf(path, sizeof path, "%s/%s.json", tmp, tag);
    snprintf(dir, dir_size, "%s/out_%s", tmp, tag);
    char *out = cJSON_Print(scene);
    cJSON_Delete(scene);
    FILE *f = fopen(path, "wb");
    if (f && out) fputs(out, f);
    if (f) fclose(f);
    free(out);
    static char so[1 << 16];
    snprintf(args, sizeof args, "run %s --out %s --quiet --overwrite", path, dir);
    return test_run_cli(args, so, sizeof so, se, se_size);
}

int main(void)
{
    const char *tmp = test_tmpdir();
    char cache[512], dir[1024], se[1 << 14];
    snprintf(cache, sizeof cache, "%s/cache", tmp);
    setenv("SEM_CACHE_DIR", cache, 1);
    /* the end turns over in 0.5 s (frame 25) and rests on the lower half from then on; the
     * sanitizer builds run 5 frames of it and not the run without self-contact */
    int sanitized = getenv("SEM_SANITIZED") != NULL;
    int frames = sanitized ? 30 : 50;

    /* the fold, self-contact at its default */
    int rc = run_scene("beam_fold", "fold_on", frames, -1, tmp, dir, sizeof dir, se, sizeof se);
    CHECK(rc == 0, "beam_fold: exit %d: %s", rc, se);
    int worst;
    long on = run_crossings(dir, frames, 1, 0, &worst);
    cJSON *s = test_read_summary(dir);
    double gap = INFINITY;
    int touched = 0;
    const cJSON *fr;
    const cJSON *frames_json = s ? cJSON_GetObjectItemCaseSensitive(s, "frames") : NULL;
    cJSON_ArrayForEach(fr, frames_json)
    {
        const cJSON *g = cJSON_GetObjectItemCaseSensitive(fr, "min_gap");
        if (cJSON_IsNumber(g)) gap = fmin(gap, g->valuedouble);
        if (num(fr, "self_contacts") > 0) touched++;
    }
    printf("beam_fold, self-contact on: %ld crossing triangle pairs over %d frames (most at frame %d), "
           "smallest gap %.4g m, self contacts in %d frames, status %s\n",
           on, frames, worst, gap, touched,
           s && cJSON_IsString(cJSON_GetObjectItemCaseSensitive(s, "status"))
               ? cJSON_GetObjectItemCaseSensitive(s, "status")->valuestring
               : "?");
    CHECK(on == 0, "beam_fold: %ld crossing pairs with self-contact on (most at frame %d)", on, worst);
    CHECK(touched >= (sanitized ? 3 : 15), "beam_fold: the folded half touched the lower one in %d frames only", touched);
    CHECK(gap > -0.001, "beam_fold: a point %.3g m deep (1 %% of the beam's height allowed)", -gap);
    cJSON_Delete(s);

    /* the same without self-contact: the folded half passes through */
    if (!sanitized) {
        rc = run_scene("beam_fold", "fold_off", frames, 0, tmp, dir, sizeof dir, se, sizeof se);
        CHECK(rc == 0, "beam_fold, self off: exit %d: %s", rc, se);
        long off = run_crossings(dir, frames, 1, 0, &worst);
        printf("beam_fold, self-contact off: %ld crossing triangle pairs (most at frame %d)\n", off, worst);
        CHECK(off > 0, "beam_fold without self-contact does not cross itself: the check above proves nothing");
    }

    /* a lone object in the air with contact.self true: contact is on without a collider
     * (the structured solver is left for the q-space one); a plain fall, nothing touches */
    rc = run_scene("box_drop", "lone", 3, 1, tmp, dir, sizeof dir, se, sizeof se);
    CHECK(rc == 0, "box_drop, contact.self true: exit %d: %s", rc, se);

    /* a wrong value is a one-line error naming the key */
    {
        char path[1200];
        snprintf(path, sizeof path, "%s/bad.json", tmp);
        FILE *f = fopen(path, "wb");
        if (f) {
            fputs("{\"objects\": [{\"primitive\": {\"type\": \"box\"}}], \"contact\": {\"self\": 2}}", f);
            fclose(f);
        }
        char args[1400];
        snprintf(args, sizeof args, "run %s --out %s/bad_out --quiet", path, tmp);
        rc = test_run_cli(args, NULL, 0, se, sizeof se);
        CHECK(rc != 0 && strstr(se, "contact.self") && !strchr(strchr(se, '\n') ? strchr(se, '\n') + 1 : "", '\n'),
              "contact.self 2: exit %d, '%s'", rc, se);
    }
    return test_finish("test_self_contact");
}
