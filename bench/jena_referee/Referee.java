// Apache Jena 4.5 as a referee: parse rules files and run GenericRuleReasoner on data.
// Usage: java -cp <jena jars> Referee JOBS, where each line of the file JOBS is one job:
//   parse <TAB> RULES <TAB> OUT          OUT gets "ok N" (N rules) or "error: message"
//   run <TAB> MODE <TAB> RULES <TAB> OUT <TAB> DATA[,DATA...]
//        MODE: forward | forwardRETE | hybrid; OUT gets the closure as sorted N-Triples,
//        or "error: message" when Jena fails, "timeout: ..." after 30 s (and the JVM
//        exits with status 3 so that no stuck thread spoils the next jobs).
//   steps <TAB> MODE <TAB> RULES <TAB> OUT <TAB> STEPS
//        STEPS holds N-Triples lines prefixed "+ " (add) or "- " (remove), and "=" lines;
//        at each "=" the closure is appended to OUT after a line "# state N".
import java.io.*;
import java.nio.file.*;
import java.util.*;
import org.apache.jena.rdf.model.*;
import org.apache.jena.reasoner.rulesys.*;
import org.apache.jena.riot.*;

public class Referee {
    static final int LIMIT_SECONDS = 30;
    static final String BASE = "http://jena.test/data/";

    public static void main(String[] args) throws Exception {
        for (String line : Files.readAllLines(Paths.get(args[0]))) {
            if (line.isBlank()) continue;
            String[] job = line.split("\t");
            String out = job[0].equals("parse") ? job[2] : job[3];
            String[] result = {"timeout: Jena gave no answer in " + LIMIT_SECONDS + " s\n"};
            Thread worker = new Thread(() -> {
                try {
                    result[0] = job[0].equals("parse") ? parse(job[1])
                            : job[0].equals("steps") ? steps(job[1], job[2], job[4])
                            : run(job[1], job[2], job[4]);
                } catch (Throwable e) {
                    result[0] = "error: " + e.getClass().getSimpleName() + ": " + e.getMessage() + "\n";
                }
            });
            worker.setDaemon(true);
            worker.start();
            worker.join(LIMIT_SECONDS * 1000L);
            Files.write(Paths.get(out), result[0].getBytes("UTF-8"));
            if (worker.isAlive()) System.exit(3);  // the caller runs the remaining jobs anew

        }
    }

    static List<Rule> rules(String path) {
        return Rule.rulesFromURL(Paths.get(path).toUri().toString());
    }

    static String parse(String path) {
        return "ok " + rules(path).size() + "\n";
    }

    static InfModel infer(String mode, String path, Model model) {
        GenericRuleReasoner reasoner = new GenericRuleReasoner(rules(path));
        reasoner.setMode(mode.equals("forward") ? GenericRuleReasoner.FORWARD
                : mode.equals("forwardRETE") ? GenericRuleReasoner.FORWARD_RETE
                : GenericRuleReasoner.HYBRID);
        return ModelFactory.createInfModel(reasoner, model);
    }

    static String steps(String mode, String path, String file) throws IOException {
        InfModel inf = infer(mode, path, ModelFactory.createDefaultModel());
        StringBuilder b = new StringBuilder();
        int state = 0;
        for (String line : Files.readAllLines(Paths.get(file))) {
            if (line.startsWith("=")) {
                b.append("# state ").append(state++).append('\n').append(closure(inf));
                continue;
            }
            Model one = ModelFactory.createDefaultModel();
            RDFDataMgr.read(one, new StringReader(line.substring(2)), null, Lang.NTRIPLES);
            if (line.startsWith("+")) inf.add(one); else inf.remove(one);
        }
        return b.toString();
    }

    static String run(String mode, String path, String data) {
        Model model = ModelFactory.createDefaultModel();
        // A fixed base (not the file's own path), so that relative IRIs in the data resolve
        // the same wherever the repository is checked out.
        for (String file : data.split(","))
            if (!file.isEmpty())
                RDFDataMgr.read(model, file, BASE + Paths.get(file).getFileName(), null);
        return closure(infer(mode, path, model));
    }

    static String closure(InfModel inf) {
        Model out = ModelFactory.createDefaultModel();
        out.add(inf.listStatements());
        StringWriter w = new StringWriter();
        RDFDataMgr.write(w, out, Lang.NTRIPLES);
        TreeSet<String> lines = new TreeSet<>();
        for (String l : w.toString().split("\n")) if (!l.isBlank()) lines.add(l);
        StringBuilder b = new StringBuilder();
        for (String l : lines) b.append(l).append('\n');
        return b.toString();
    }
}
