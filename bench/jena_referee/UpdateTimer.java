// Apache Jena 4.5 timing the update of bench/rules_scaling.py, in process, for a side-by-side ratio.
// Usage: java -cp <jena jars> UpdateTimer JOBS, where each line of the file JOBS is one case:
//   RULES <TAB> DATA <TAB> N <TAB> RUNS <TAB> WARMUP <TAB> CLOCK
// RULES holds N rules shaped as the paper's Figure 5 (see paper_rules in rules_scaling.py),
// DATA the ontology, the robot and its N settings (N-Triples); CLOCK is "wall" or "cpu" (the
// CPU time of the thread running Jena: the JVM's own threads, JIT and garbage collector, do not
// count; after the warm-up they have little left to do).
// For each case: one GenericRuleReasoner in FORWARD_RETE mode over the data, prepared; then
// WARMUP untimed and RUNS timed rounds of: the battery update (level "normal" -> "very low")
// and reading the matches (the mobile base's triples, N of them "low"), timed; then the update
// reverted, untimed. Prints one JSON object per case: {"rules": N, "samples_ms": [...]}.
import java.lang.management.ManagementFactory;
import java.lang.management.ThreadMXBean;
import java.nio.file.*;
import java.util.*;
import org.apache.jena.graph.*;
import org.apache.jena.rdf.model.*;
import org.apache.jena.reasoner.rulesys.*;
import org.apache.jena.riot.*;

public class UpdateTimer {
    static final String AC = "https://w3id.org/tspace/selfconfig#";
    static final ThreadMXBean THREADS = ManagementFactory.getThreadMXBean();

    public static void main(String[] args) throws Exception {
        for (String line : Files.readAllLines(Paths.get(args[0]))) {
            if (line.isBlank()) continue;
            String[] job = line.split("\t");
            int n = Integer.parseInt(job[2]);
            double[] samples = measure(job[0], job[1], n, Integer.parseInt(job[3]),
                    Integer.parseInt(job[4]), job[5].equals("cpu"));
            StringBuilder b = new StringBuilder("{\"rules\": " + n + ", \"samples_ms\": [");
            for (int i = 0; i < samples.length; i++) b.append(i > 0 ? ", " : "").append(samples[i]);
            System.out.println(b.append("]}"));
            System.out.flush();
        }
    }

    static long now(boolean cpu) {
        return cpu ? THREADS.getCurrentThreadCpuTime() : System.nanoTime();
    }

    static double[] measure(String rulesPath, String dataPath, int n, int runs, int warmup,
            boolean cpu) {
        GenericRuleReasoner reasoner =
                new GenericRuleReasoner(Rule.rulesFromURL(Paths.get(rulesPath).toUri().toString()));
        reasoner.setMode(GenericRuleReasoner.FORWARD_RETE);
        Model data = ModelFactory.createDefaultModel();
        RDFDataMgr.read(data, dataPath, Lang.NTRIPLES);
        InfModel inf = ModelFactory.createInfModel(reasoner, data);
        inf.prepare();
        Resource battery = inf.createResource(AC + "robot1_battery");
        Resource base = inf.createResource(AC + "robot1_base");
        Property level = inf.createProperty(AC + "battery_level");
        Statement normal = inf.createStatement(battery, level, "normal");
        Statement low = inf.createStatement(battery, level, "very low");
        List<Statement> lows = new ArrayList<>();
        List<Statement> normals = new ArrayList<>();
        for (int i = 0; i < n; i++) {
            Property setting = inf.createProperty(AC + "setting_" + i);
            lows.add(inf.createStatement(base, setting, "low"));
            normals.add(inf.createStatement(base, setting, "normal"));
        }
        double[] samples = new double[runs];
        for (int round = 0; round < warmup + runs; round++) {
            long start = now(cpu);
            inf.remove(normal);
            inf.add(low);
            int found = 0;
            for (StmtIterator it = inf.listStatements(base, null, (RDFNode) null); it.hasNext(); ) {
                if (it.next().getObject().toString().equals("low")) found++;
            }
            long took = now(cpu) - start;
            if (found != n) throw new IllegalStateException(n + " rules: " + found + " conclusions");
            if (round >= warmup) samples[round - warmup] = took / 1e6;
            inf.remove(low);
            inf.add(normal);
            inf.remove(lows);
            inf.add(normals);
            for (Statement s : lows) {
                if (inf.contains(s)) throw new IllegalStateException("not reverted: " + s);
            }
        }
        return samples;
    }
}
